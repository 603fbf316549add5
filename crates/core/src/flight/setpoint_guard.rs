//! The flight part's check of a mission target against the latest revolution.
//!
//! The companion guards its commands on the scan in its own map frame, with its SLAM pose,
//! and the autopilot flies them on its own estimate. While the two agree the check here binds
//! no harder than the companion's; when they do not (a SLAM whose heading slid off while its
//! fixes were refused, a home point placed by a SLAM pose a metre from the estimate's), it is
//! the only check of what is actually flown. The position loop is proportional, so the target
//! stands for the velocity `gain · (target − here)`: that velocity, within the loop's output
//! limit, is turned into the body frame by the estimated heading (the frame the scan was taken
//! in), guarded, and turned back into a target.

use crate::geom::Vec2;
use crate::guidance::guard::{limit_approach, ApproachLimit, Guard};
use crate::guidance::nearest_hits::NearestHits;
use crate::msgs::EstimatedState;
use libm::sincosf;

/// The target (world x, y) whose velocity respects every hit, or `None` when `target` already
/// does (or the loop has no gain to invert). `gain` (1/s) and `max_speed_m_s` (per axis) are
/// the position loop's.
pub fn guard_target(
    target: [f32; 2],
    e: &EstimatedState,
    hits: &NearestHits,
    limit: &ApproachLimit,
    gain: f32,
    max_speed_m_s: f32,
) -> Option<[f32; 2]> {
    if !(gain > 0.0 && e.yaw_rad.is_finite()) {
        return None;
    }
    let here = [e.position_m[0], e.position_m[1]];
    let axis = |i: usize| (gain * (target[i] - here[i])).clamp(-max_speed_m_s, max_speed_m_s);
    let (vx, vy) = (axis(0), axis(1));
    // Only hits whose allowance is below the speed can bind (the guard skips the others):
    // those nearer than `r_min + speed / rate`, a few at most, none on most steps.
    let reach_m = limit.r_min_m + libm::sqrtf(vx * vx + vy * vy) / limit.approach_rate_1_s;
    hits.closer_than(reach_m).next()?;
    let (s, c) = sincosf(e.yaw_rad);
    let body = Vec2::new(c * vx + s * vy, c * vy - s * vx);
    let (safe, action) = limit_approach(body, || hits.closer_than(reach_m), limit);
    if action == Guard::Clear {
        return None;
    }
    let world = [c * safe.x - s * safe.y, s * safe.x + c * safe.y];
    Some([here[0] + world[0] / gain, here[1] + world[1] / gain])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::{Beam, Scan};

    fn facing(yaw_rad: f32) -> EstimatedState {
        EstimatedState {
            yaw_rad,
            ..EstimatedState::default()
        }
    }

    #[test]
    fn a_target_toward_a_near_wall_is_pulled_back_in_the_estimates_frame() {
        let limit = ApproachLimit {
            r_min_m: 0.5,
            approach_rate_1_s: 1.0,
        };
        // A wall 0.6 m ahead of the body (bearing 0), the body facing world +y.
        let mut scan: Scan<1> = Scan::new(0.0);
        scan.push(Beam::new(0.0, 0.6)).unwrap();
        let hits = NearestHits::of_scan(&scan);
        let e = facing(core::f32::consts::FRAC_PI_2);
        // Asked for 0.5 m/s toward world +y (into the wall): 0.1 m/s allowed.
        let t = guard_target([0.0, 0.5], &e, &hits, &limit, 1.0, 1.0).expect("limited");
        assert!(t[0].abs() < 1e-5 && (t[1] - 0.1).abs() < 1e-5, "{t:?}");
        // Along world x (along the wall) or away from it: left alone.
        assert_eq!(guard_target([0.5, 0.0], &e, &hits, &limit, 1.0, 1.0), None);
        assert_eq!(guard_target([0.0, -0.5], &e, &hits, &limit, 1.0, 1.0), None);
    }
}
