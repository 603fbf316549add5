//! Getting out of a mover's way: a velocity obstacle (Fiorini and Shiller) over a handful of
//! candidate velocities. The mover is a disc of its seen half width plus `r_min` round its
//! estimated centre, moving at its estimated velocity; a candidate whose motion relative to it
//! enters the disc within `evade_horizon_s` is penalised the sooner it would, and among the
//! rest the one nearest to what the rules asked wins. Each candidate is judged after the
//! clearance guard has limited it against the walls, so stepping aside never trades a person
//! for a wall: `r_min` toward every fixed hit holds as before.
//!
//! A walker coming straight on faster than the vehicle flies cannot be outrun along its line;
//! the candidates across its way are the ones that leave its disc, and the side with the room
//! to do so is the one that survives the guard.

use super::config::GuidanceConfig;
use super::guard::guard_velocity;
use super::movers::Mover;
use super::sweep::Sweep;
use crate::geom::Vec2;
use core::f32::consts::TAU;
use libm::{cosf, sinf, sqrtf};

/// Directions tried round the compass (15° apart), each at the speed limit and at half of it.
const HEADINGS: usize = 24;
/// Weight of a contact within the horizon against the squared distance from the wish (in
/// units of the squared speed limit): any candidate that misses beats any that does not.
const CONTACT_WEIGHT: f32 = 10.0;

/// The velocity (sensor frame, m/s, guarded against every fixed hit) that keeps clear of
/// `mover` and stays nearest to `wish`.
pub(super) fn evade<const N: usize, I: Iterator<Item = (Vec2, f32)>>(
    mover: &Mover,
    wish: Vec2,
    sweep: &Sweep<N>,
    remembered: impl Fn() -> I,
    cfg: &GuidanceConfig,
) -> Vec2 {
    let v_max = cfg.max_speed_m_s;
    let compass = (0..HEADINGS).flat_map(|k| {
        let a = k as f32 * TAU / HEADINGS as f32;
        let d = Vec2::new(cosf(a), sinf(a));
        [d * v_max, d * (0.5 * v_max)]
    });
    let mut best = (f32::INFINITY, Vec2::ZERO);
    for candidate in core::iter::once(wish).chain(compass).chain([Vec2::ZERO]) {
        let (v, _) = guard_velocity(candidate, sweep, &remembered, cfg);
        let cost = (v - wish).norm_squared() / (v_max * v_max)
            + CONTACT_WEIGHT * contact_risk(v, mover, cfg);
        if cost < best.0 {
            best = (cost, v);
        }
    }
    best.1
}

/// 0 when flying `v` keeps out of the mover's disc for the whole horizon; up to 1 the sooner
/// it enters; from 1 up when already inside, the more the faster it closes.
pub fn contact_risk(v: Vec2, mover: &Mover, cfg: &GuidanceConfig) -> f32 {
    let reach = cfg.r_min_m() + mover.half_width_m;
    let relative = v - mover.velocity_m_s;
    let d = mover.centre_m;
    let distance = d.norm();
    if distance <= reach {
        let closing = relative.dot(d) / distance.max(1e-6);
        return 1.0 + (closing / cfg.max_speed_m_s).max(-1.0);
    }
    // First t ≥ 0 with |d − relative·t| = reach.
    let a = relative.norm_squared();
    let b = relative.dot(d);
    let c = distance * distance - reach * reach;
    let disc = b * b - a * c;
    if a <= 0.0 || b <= 0.0 || disc < 0.0 {
        return 0.0;
    }
    let t = (b - sqrtf(disc)) / a;
    if t > cfg.evade_horizon_s {
        return 0.0;
    }
    1.0 - t / cfg.evade_horizon_s
}
