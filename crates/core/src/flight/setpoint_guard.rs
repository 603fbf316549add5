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

/// The position loop's gain and output limit, and the velocity loop's time constant: what
/// turns a target into the velocity the vehicle will actually fly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loops {
    /// Position loop gain, 1/s.
    pub gain_1_s: f32,
    /// Position loop output limit per axis, m/s.
    pub max_speed_m_s: f32,
    /// Velocity loop time constant (1 / its gain), s.
    pub response_s: f32,
}

/// The target (world x, y) whose velocity respects every hit, or `None` when `target` already
/// does (or the loop has no gain to invert).
pub fn guard_target(
    target: [f32; 2],
    e: &EstimatedState,
    hits: &NearestHits,
    limit: &ApproachLimit,
    loops: &Loops,
) -> Option<[f32; 2]> {
    let gain = loops.gain_1_s;
    if !(gain > 0.0 && e.yaw_rad.is_finite() && e.velocity_m_s.iter().all(|v| v.is_finite())) {
        return None;
    }
    let here = [e.position_m[0], e.position_m[1]];
    let max = loops.max_speed_m_s;
    let axis = |i: usize| (gain * (target[i] - here[i])).clamp(-max, max);
    let (vx, vy) = (axis(0), axis(1));
    let (s, c) = sincosf(e.yaw_rad);
    let to_body = |x: f32, y: f32| Vec2::new(c * x + s * y, c * y - s * x);
    let flying = to_body(e.velocity_m_s[0], e.velocity_m_s[1]);
    let lag_m = |u: Vec2| loops.response_s.max(0.0) * flying.dot(u).max(0.0);
    // Only hits whose allowance is below the speed can bind (the guard skips the others):
    // those nearer than `r_min + speed / rate` once shortened by the lag, a few at most, none
    // on most steps.
    let reach_m = limit.r_min_m
        + libm::sqrtf(vx * vx + vy * vy) / limit.approach_rate_1_s
        + loops.response_s.max(0.0) * flying.norm();
    hits.closer_than(reach_m).next()?;
    let body = to_body(vx, vy);
    let ahead = || hits.closer_than(reach_m).map(|(u, r)| (u, r - lag_m(u)));
    let (safe, action) = limit_approach(body, ahead, limit);
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

    const LOOPS: Loops = Loops {
        gain_1_s: 1.0,
        max_speed_m_s: 1.0,
        response_s: 0.25,
    };

    const LIMIT: ApproachLimit = ApproachLimit {
        r_min_m: 0.5,
        approach_rate_1_s: 1.0,
    };

    #[test]
    fn a_target_toward_a_near_wall_is_pulled_back_in_the_estimates_frame() {
        // A wall 0.6 m ahead of the body (bearing 0), the body facing world +y, hovering.
        let mut scan: Scan<1> = Scan::new(0.0);
        scan.push(Beam::new(0.0, 0.6)).unwrap();
        let hits = NearestHits::of_scan(&scan);
        let e = facing(core::f32::consts::FRAC_PI_2);
        // Asked for 0.5 m/s toward world +y (into the wall): 0.1 m/s allowed.
        let t = guard_target([0.0, 0.5], &e, &hits, &LIMIT, &LOOPS).expect("limited");
        assert!(t[0].abs() < 1e-5 && (t[1] - 0.1).abs() < 1e-5, "{t:?}");
        // Along world x (along the wall) or away from it: left alone.
        assert_eq!(guard_target([0.5, 0.0], &e, &hits, &LIMIT, &LOOPS), None);
        assert_eq!(guard_target([0.0, -0.5], &e, &hits, &LIMIT, &LOOPS), None);
    }

    #[test]
    fn a_vehicle_already_closing_on_a_wall_is_braked_before_r_min() {
        // 0.7 m from a wall ahead, flying at it at 0.4 m/s: the velocity loop will cover
        // 0.25 s x 0.4 m/s = 0.1 m more before it takes up a lower command, so the wall counts
        // as 0.6 m away and 0.1 m/s is all that may be asked of the 0.15 m/s asked, which the
        // range alone (0.2 m/s) allows.
        let mut scan: Scan<1> = Scan::new(0.0);
        scan.push(Beam::new(0.0, 0.7)).unwrap();
        let hits = NearestHits::of_scan(&scan);
        let closing = EstimatedState {
            velocity_m_s: [0.4, 0.0, 0.0],
            ..facing(0.0)
        };
        let t = guard_target([0.15, 0.0], &closing, &hits, &LIMIT, &LOOPS).expect("braked");
        assert!((t[0] - 0.1).abs() < 1e-5 && t[1].abs() < 1e-6, "{t:?}");
        // Flying as fast away from it, or along it, the range alone sets the rule.
        for v in [[-0.4, 0.0, 0.0], [0.0, 0.4, 0.0]] {
            let e = EstimatedState {
                velocity_m_s: v,
                ..facing(0.0)
            };
            assert_eq!(guard_target([0.15, 0.0], &e, &hits, &LIMIT, &LOOPS), None);
        }
        // Closing so fast that no approach is allowed: zero toward the wall, never a demand to
        // back off (a door's other jamb may forbid that).
        let fast = EstimatedState {
            velocity_m_s: [1.0, 0.0, 0.0],
            ..facing(0.0)
        };
        let t = guard_target([0.2, 0.3], &fast, &hits, &LIMIT, &LOOPS).expect("stopped");
        assert!(t[0].abs() < 1e-5 && (t[1] - 0.3).abs() < 1e-5, "{t:?}");
    }
}
