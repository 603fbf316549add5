//! The last word on every command: limits the speed toward each hit so the vehicle slows
//! exponentially as it nears `r_min` and never closes on it, whatever mode or rule produced
//! the command. Safety-critical.

use super::config::GuidanceConfig;
use super::sweep::{usable, Sweep};
use crate::geom::Vec2;
use crate::scan::Scan;
use libm::{cosf, sinf};

/// What the guard did to the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Guard {
    /// The command already respected every hit.
    Clear,
    /// The speed toward at least one hit was reduced.
    Limited,
    /// No command close to the request respected every hit: zero velocity.
    Stopped,
}

/// Largest allowed speed toward a hit at `range_m`, m/s: `approach_rate · (r − r_min)`, at least 0.
pub fn allowed_approach_m_s(range_m: f32, cfg: &GuidanceConfig) -> f32 {
    (cfg.approach_rate_1_s * (range_m - cfg.r_min_m())).max(0.0)
}

/// Removes from `v` (sensor frame, m/s) what exceeds the allowed approach speed to any hit of
/// the sweep or any remembered one (`remembered` gives unit direction and range, body frame).
pub(super) fn guard_velocity<const N: usize, I: Iterator<Item = (Vec2, f32)>>(
    v: Vec2,
    sweep: &Sweep<N>,
    remembered: impl Fn() -> I,
    cfg: &GuidanceConfig,
) -> (Vec2, Guard) {
    let hits = || {
        (0..sweep.len())
            .filter(|&pos| sweep.is_usable(pos))
            .map(|pos| (sweep.unit(pos), sweep.range_m(pos)))
            .chain(remembered())
    };
    // Each correction only shortens `v`, so hits whose allowance exceeds the current speed can
    // never be violated and are skipped.
    let mut out = v;
    let mut touched = false;
    for _ in 0..3 {
        let mut changed = false;
        for (u, range) in hits() {
            let limit = allowed_approach_m_s(range, cfg);
            if limit * limit >= out.norm_squared() {
                continue;
            }
            let toward = out.dot(u);
            if toward > limit {
                out = out - u * (toward - limit);
                changed = true;
            }
        }
        touched |= changed;
        if !changed {
            break;
        }
    }
    if !respects(out, hits(), cfg) {
        // Between two near sides (a passage not much wider than 2 r_min) each correction
        // breaks the other side's limit and the passes do not settle; the same command,
        // slowed until it respects every hit, still moves on rather than stopping dead.
        out = out * largest_respecting_fraction(out, hits(), cfg);
        touched = true;
        if out == Vec2::ZERO {
            return (Vec2::ZERO, Guard::Stopped);
        }
    }
    let action = if touched {
        Guard::Limited
    } else {
        Guard::Clear
    };
    (out, action)
}

/// True when `v` (sensor frame, m/s) approaches no hit of `scan` faster than allowed (to
/// 0.1 mm/s): the guard's promise, checkable from outside.
pub fn respects_every_hit<const N: usize>(v: Vec2, scan: &Scan<N>, cfg: &GuidanceConfig) -> bool {
    let hits = scan.beams().iter().filter(|b| usable(b));
    respects(
        v,
        hits.map(|b| (Vec2::new(cosf(b.angle_rad), sinf(b.angle_rad)), b.range_m)),
        cfg,
    )
}

/// The largest `s` in [0, 1] for which `s · v` approaches no hit faster than allowed: every
/// limit is at least 0, so slowing down along `v` always ends inside them.
fn largest_respecting_fraction(
    v: Vec2,
    hits: impl Iterator<Item = (Vec2, f32)>,
    cfg: &GuidanceConfig,
) -> f32 {
    hits.fold(1.0f32, |s, (u, range)| {
        let toward = v.dot(u);
        let limit = allowed_approach_m_s(range, cfg);
        if toward > limit {
            s.min(limit / toward)
        } else {
            s
        }
    })
}

fn respects(v: Vec2, mut hits: impl Iterator<Item = (Vec2, f32)>, cfg: &GuidanceConfig) -> bool {
    let speed = v.norm();
    hits.all(|(u, range)| {
        let limit = allowed_approach_m_s(range, cfg);
        limit >= speed || v.dot(u) <= limit + 1e-4
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::Beam;
    use core::f32::consts::PI;

    #[test]
    fn the_speed_toward_a_near_wall_is_cut_to_the_allowance_and_the_rest_kept() {
        let cfg = GuidanceConfig::default();
        let mut scan: Scan<2> = Scan::new(0.0);
        scan.push(Beam::new(0.0, cfg.r_min_m() + 0.1)).unwrap();
        let sweep = Sweep::new(&scan, cfg.rule_start_rad);
        let none = || core::iter::empty();
        let (v, g) = guard_velocity(Vec2::new(0.4, 0.3), &sweep, none, &cfg);
        assert_eq!(g, Guard::Limited);
        assert!((v.x - 0.1 * cfg.approach_rate_1_s).abs() < 1e-5 && (v.y - 0.3).abs() < 1e-6);
        // Away from the wall: untouched. Inside r_min: no approach at all.
        assert_eq!(
            guard_velocity(Vec2::new(-0.4, 0.3), &sweep, none, &cfg),
            (Vec2::new(-0.4, 0.3), Guard::Clear)
        );
        let mut inside: Scan<2> = Scan::new(0.0);
        inside.push(Beam::new(0.0, 0.2)).unwrap();
        let sweep = Sweep::new(&inside, cfg.rule_start_rad);
        let (v, _) = guard_velocity(Vec2::new(0.4, 0.0), &sweep, none, &cfg);
        assert!(v.x.abs() < 1e-6);
    }

    #[test]
    fn between_two_near_sides_the_command_is_slowed_not_stopped() {
        // A passage 1.1 m wide, centred: each side 0.05 m beyond r_min. Cutting the approach
        // to one side's hits ahead adds speed toward the other's, and the passes never settle.
        let cfg = GuidanceConfig::default();
        let half = cfg.r_min_m() + 0.05;
        let mut scan: Scan<72> = Scan::new(0.0);
        for k in 0..72 {
            let a = -PI + (k as f32 + 0.5) * (2.0 * PI / 72.0);
            let s = sinf(a).abs();
            let range = if s > 0.05 { half / s } else { 20.0 };
            scan.push(Beam::new(a, range.min(20.0))).unwrap();
        }
        let sweep = Sweep::new(&scan, cfg.rule_start_rad);
        let none = || core::iter::empty();
        let ahead = Vec2::new(0.4, 0.02);
        let (v, g) = guard_velocity(ahead, &sweep, none, &cfg);
        assert_eq!(g, Guard::Limited, "{v:?}");
        assert!(v.x > 0.05, "{v:?}");
        assert!(respects_every_hit(v, &scan, &cfg), "{v:?}");
    }
}
