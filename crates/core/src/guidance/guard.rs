//! The last word on every command: limits the speed toward each hit so the vehicle slows
//! exponentially as it nears `r_min` and never closes on it, whatever mode or rule produced
//! the command. Safety-critical.
//!
//! The same rule ([`limit_approach`]) runs twice: in the guidance, on the companion's side, and
//! in the flight part on the setpoint it is about to fly ([`super::nearest_hits`]). The
//! guidance turns its guarded body-frame command into the world with the companion's pose,
//! and the flight part flies it with its own estimate: when the two disagree (a SLAM heading
//! gone wrong, a position setpoint placed by a SLAM pose the estimate no longer shares) what
//! is flown is not what was guarded, and only the flight part's own check holds.

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

/// The guard's rule: the largest speed toward a hit at range `r` is
/// `approach_rate · (r − r_min)`, at least 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApproachLimit {
    /// Closest a hit may come, m (vehicle radius plus margin).
    pub r_min_m: f32,
    /// Speed allowed toward a hit per metre of range beyond `r_min_m`, 1/s.
    pub approach_rate_1_s: f32,
}

impl ApproachLimit {
    /// Largest allowed speed toward a hit at `range_m`, m/s.
    pub fn allowed_m_s(&self, range_m: f32) -> f32 {
        (self.approach_rate_1_s * (range_m - self.r_min_m)).max(0.0)
    }
}

impl From<&GuidanceConfig> for ApproachLimit {
    fn from(cfg: &GuidanceConfig) -> Self {
        Self {
            r_min_m: cfg.r_min_m(),
            approach_rate_1_s: cfg.approach_rate_1_s,
        }
    }
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
    limit_approach(v, hits, &ApproachLimit::from(cfg))
}

/// Removes from `v` (m/s) what exceeds `limit`'s allowed approach speed to any of `hits` (unit
/// direction and range, in the frame of `v`).
pub fn limit_approach<I: Iterator<Item = (Vec2, f32)>>(
    v: Vec2,
    hits: impl Fn() -> I,
    limit: &ApproachLimit,
) -> (Vec2, Guard) {
    // Each correction only shortens `v`, so hits whose allowance exceeds the current speed can
    // never be violated and are skipped.
    let mut out = v;
    let mut touched = false;
    for _ in 0..3 {
        let mut changed = false;
        for (u, range) in hits() {
            let allowed = limit.allowed_m_s(range);
            if allowed * allowed >= out.norm_squared() {
                continue;
            }
            let toward = out.dot(u);
            if toward > allowed {
                out = out - u * (toward - allowed);
                changed = true;
            }
        }
        touched |= changed;
        if !changed {
            break;
        }
    }
    if !respects(out, hits(), limit) {
        return (Vec2::ZERO, Guard::Stopped);
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
        &ApproachLimit::from(cfg),
    )
}

fn respects(v: Vec2, mut hits: impl Iterator<Item = (Vec2, f32)>, limit: &ApproachLimit) -> bool {
    let speed = v.norm();
    hits.all(|(u, range)| {
        let allowed = limit.allowed_m_s(range);
        allowed >= speed || v.dot(u) <= allowed + 1e-4
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::Beam;

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
}
