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
//! to do so is the one that survives the guard. The guard only limits a candidate now; over the
//! horizon the vehicle also stops where the candidate's line comes within `r_min` of a wall, so
//! each candidate's motion is cut short there when its contact risk is judged: running ahead of
//! a walker toward the wall at the end of its way looks safe for the first second and is a
//! trap.

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
/// Cost of passing a mover on the other side than before: half the disc's radius of contact
/// risk. Each side's risk is judged from a velocity tracked over a few revolutions, and with a
/// quarter of the radius that velocity's swings alone turned the vehicle from side to side
/// along a walker's line, slower than the walker, instead of leaving it; a wall
/// closing the chosen side (the guard stopping the vehicle in the walker's way) costs more and
/// still turns it round.
const SIDE_SWITCH_COST: f32 = 50.0;
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
    let hits = || {
        (0..sweep.len())
            .filter(|&pos| sweep.is_usable(pos))
            .map(|pos| (sweep.unit(pos), sweep.range_m(pos)))
            .chain(remembered())
    };
    let mut best = (f32::INFINITY, Vec2::ZERO);
    for candidate in core::iter::once(wish).chain(compass).chain([Vec2::ZERO]) {
        let (v, _) = guard_velocity(candidate, sweep, &remembered, cfg);
        let switch = side.is_some_and(|s| s * side_of(v, mover) < 0.0);
        let free_m = free_travel_m(v, hits(), cfg.r_min_m());
        let cost = (v - wish).norm_squared() / (v_max * v_max)
            + CONTACT_WEIGHT * contact_risk(v, free_m, mover, cfg)
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

/// How far the vehicle can fly along `v` before its centre comes within `r_min_m` of one of
/// `hits` (unit direction and range, sensor frame), m: 0 when it is already that close to a
/// hit ahead, infinite for zero velocity or open space.
pub fn free_travel_m(v: Vec2, hits: impl Iterator<Item = (Vec2, f32)>, r_min_m: f32) -> f32 {
    let speed = v.norm();
    if speed <= 0.0 {
        return f32::INFINITY;
    }
    let e = v * (1.0 / speed);
    let mut free = f32::INFINITY;
    for (u, range) in hits {
        let ahead = u.dot(e) * range;
        if ahead <= 0.0 {
            continue;
        }
        // Along the line, the distance to the hit is r_min where s² − 2·ahead·s + range² − r² = 0.
        let disc = ahead * ahead - range * range + r_min_m * r_min_m;
        if disc >= 0.0 {
            free = free.min((ahead - libm::sqrtf(disc)).max(0.0));
        }
    }
    free
}

/// How deep flying `v` takes the vehicle into the mover's disc within the horizon, as a share
/// of the disc's radius: 0 when it stays out. The vehicle flies `v` for at most `free_m` (where
/// a wall stops it, [`free_travel_m`]) and then stays put while the mover walks on. The disc grows with time by what the mover's
/// estimated velocity may be off ([`SPEED_UNCERTAINTY_M_S`]), so crossing close in front of a
/// walker counts as the gamble it is; and it is the deepest point, not the first touch, so that
/// inside the disc the way out that the mover's own motion opens (across its way) beats backing
/// off along it.
pub fn contact_risk(v: Vec2, free_m: f32, mover: &Mover, cfg: &GuidanceConfig) -> f32 {
    let reach = cfg.r_min_m() + mover.half_width_m;
    let speed = v.norm();
    let stop_s = if speed > 0.0 {
        free_m / speed
    } else {
        f32::INFINITY
    };
    let mut deepest = 0.0f32;
    for k in 0..=RISK_SAMPLES {
        let t = cfg.evade_horizon_s * k as f32 / RISK_SAMPLES as f32;
        let flown = v * t.min(stop_s);
        let distance = (mover.centre_m + mover.velocity_m_s * t - flown).norm();
        deepest = deepest.max(reach + SPEED_UNCERTAINTY_M_S * t - distance);
    }
    deepest / reach
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_travel_ends_where_the_line_comes_within_r_min_of_a_hit() {
        let ahead = (Vec2::new(1.0, 0.0), 1.5);
        let behind = (Vec2::new(-1.0, 0.0), 0.6);
        let beside = (Vec2::new(0.0, 1.0), 0.6);
        let v = Vec2::new(0.4, 0.0);
        let free = free_travel_m(v, [ahead, behind, beside].into_iter(), 0.5);
        assert!((free - 1.0).abs() < 1e-5, "{free}");
        // A hit off the line by more than r_min never stops the vehicle; nor does zero speed.
        let off = (Vec2::new(0.6, 0.8), 1.0);
        assert_eq!(free_travel_m(v, [off].into_iter(), 0.5), f32::INFINITY);
        assert_eq!(
            free_travel_m(Vec2::ZERO, [ahead].into_iter(), 0.5),
            f32::INFINITY
        );
        // Already inside r_min of a hit ahead: no travel at all.
        assert_eq!(
            free_travel_m(v, [(Vec2::new(1.0, 0.0), 0.3)].into_iter(), 0.5),
            0.0
        );
    }

    #[test]
    fn running_ahead_of_a_faster_walker_into_a_wall_is_judged_the_trap_it_is() {
        let cfg = GuidanceConfig::default();
        // A walker 1.6 m behind, coming on at 0.7 m/s; the vehicle flies away at 0.5 m/s.
        let walker = Mover {
            unit: Vec2::new(1.0, 0.0),
            range_m: 1.35,
            closing_m_s: 0.7,
            centre_m: Vec2::new(1.6, 0.0),
            half_width_m: 0.25,
            velocity_m_s: Vec2::new(-0.7, 0.0),
        };
        let away = Vec2::new(-0.5, 0.0);
        let open = contact_risk(away, f32::INFINITY, &walker, &cfg);
        // A wall 1 m ahead stops the vehicle after 0.5 m; the walker keeps coming.
        let walled = contact_risk(away, 0.5, &walker, &cfg);
        assert!(walled > open + 0.3, "open {open}, walled {walled}");
        // Stepping across the walker's way is then the better choice.
        let across = Vec2::new(0.0, 0.5);
        let aside = contact_risk(across, f32::INFINITY, &walker, &cfg);
        assert!(aside < walled, "aside {aside}, walled {walled}");
    }
}
