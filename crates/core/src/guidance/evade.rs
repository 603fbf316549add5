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
use libm::{cosf, sinf};

/// Directions tried round the compass (15° apart), each at the speed limit and at half of it.
const HEADINGS: usize = 24;
/// Weight of a contact within the horizon against the squared distance from the wish (in
/// units of the squared speed limit): a centimetre of contact outweighs
/// any detour.
const CONTACT_WEIGHT: f32 = 100.0;
/// Cost of passing a mover on the other side than before: a quarter of the disc's radius of
/// contact risk, so a wall closing the chosen side still turns the vehicle round.
const SIDE_SWITCH_COST: f32 = 25.0;
/// How far off a walker's estimated velocity may be, m/s: its centre is tracked over a few
/// revolutions from the hits of one side only.
const SPEED_UNCERTAINTY_M_S: f32 = 0.15;
/// Instants of the horizon at which the distance to the mover is checked.
const RISK_SAMPLES: usize = 16;

/// The velocity (sensor frame, m/s, guarded against every fixed hit) that keeps clear of
/// `mover` and stays nearest to `wish`, and the side of the mover's line of sight it passes on
/// (+1 counter-clockwise). Once a `side` is taken, the other costs [`SIDE_SWITCH_COST`]: with a
/// walker coming straight on, both sides are about equally good, and a vehicle that picks
/// anew each revolution zig-zags along the walker's line instead of leaving it.
pub(super) fn evade<const N: usize, I: Iterator<Item = (Vec2, f32)>>(
    mover: &Mover,
    wish: Vec2,
    sweep: &Sweep<N>,
    remembered: impl Fn() -> I,
    cfg: &GuidanceConfig,
    side: Option<f32>,
) -> (Vec2, f32) {
    let v_max = cfg.max_speed_m_s;
    let compass = (0..HEADINGS).flat_map(|k| {
        let a = k as f32 * TAU / HEADINGS as f32;
        let d = Vec2::new(cosf(a), sinf(a));
        [d * v_max, d * (0.5 * v_max)]
    });
    let mut best = (f32::INFINITY, Vec2::ZERO);
    for candidate in core::iter::once(wish).chain(compass).chain([Vec2::ZERO]) {
        let (v, _) = guard_velocity(candidate, sweep, &remembered, cfg);
        let switch = side.is_some_and(|s| s * side_of(v, mover) < 0.0);
        let cost = (v - wish).norm_squared() / (v_max * v_max)
            + CONTACT_WEIGHT * contact_risk(v, mover, cfg)
            + if switch { SIDE_SWITCH_COST } else { 0.0 };
        if cost < best.0 {
            best = (cost, v);
        }
    }
    let taken = match side_of(best.1, mover) {
        s if s != 0.0 => s,
        _ => side.unwrap_or(1.0),
    };
    (best.1, taken)
}

/// +1 when `v` passes the mover's line of sight on its counter-clockwise side, -1 clockwise,
/// 0 along it.
fn side_of(v: Vec2, mover: &Mover) -> f32 {
    let c = mover.centre_m.cross(v);
    if c > 0.0 {
        1.0
    } else if c < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// How deep flying `v` takes the vehicle into the mover's disc within the horizon, as a share
/// of the disc's radius: 0 when it stays out. The disc grows with time by what the mover's
/// estimated velocity may be off ([`SPEED_UNCERTAINTY_M_S`]), so crossing close in front of a
/// walker counts as the gamble it is; and it is the deepest point, not the first touch, so that
/// inside the disc the way out that the mover's own motion opens (across its way) beats backing
/// off along it.
pub fn contact_risk(v: Vec2, mover: &Mover, cfg: &GuidanceConfig) -> f32 {
    let reach = cfg.r_min_m() + mover.half_width_m;
    let relative = v - mover.velocity_m_s;
    let mut deepest = 0.0f32;
    for k in 0..=RISK_SAMPLES {
        let t = cfg.evade_horizon_s * k as f32 / RISK_SAMPLES as f32;
        let distance = (mover.centre_m - relative * t).norm();
        deepest = deepest.max(reach + SPEED_UNCERTAINTY_M_S * t - distance);
    }
    deepest / reach
}
