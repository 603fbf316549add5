//! The last word on every command: limits the speed toward each hit so the vehicle slows
//! exponentially as it nears `r_min` and never closes on it, whatever mode or rule produced
//! the command. Safety-critical.

use super::config::GuidanceConfig;
use super::prls::usable;
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

/// Removes from `v` (sensor frame, m/s) what exceeds the allowed approach speed to any hit.
pub fn guard_velocity<const N: usize>(
    v: Vec2,
    scan: &Scan<N>,
    cfg: &GuidanceConfig,
) -> (Vec2, Guard) {
    // Each correction only shortens `v`, so hits whose allowance exceeds the current speed can
    // never be violated and are skipped cheaply.
    let mut out = v;
    let mut touched = false;
    for _ in 0..3 {
        let mut changed = false;
        for b in scan.beams().iter().filter(|b| usable(b)) {
            let limit = allowed_approach_m_s(b.range_m, cfg);
            if limit * limit >= out.norm_squared() {
                continue;
            }
            let u = Vec2::new(cosf(b.angle_rad), sinf(b.angle_rad));
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
    if !respects_every_hit(out, scan, cfg) {
        return (Vec2::ZERO, Guard::Stopped);
    }
    let action = if touched {
        Guard::Limited
    } else {
        Guard::Clear
    };
    (out, action)
}

/// True when `v` approaches no hit faster than allowed (to 0.1 mm/s).
pub fn respects_every_hit<const N: usize>(v: Vec2, scan: &Scan<N>, cfg: &GuidanceConfig) -> bool {
    scan.beams().iter().filter(|b| usable(b)).all(|b| {
        let u = Vec2::new(cosf(b.angle_rad), sinf(b.angle_rad));
        v.dot(u) <= allowed_approach_m_s(b.range_m, cfg) + 1e-4
    })
}
