//! The flight part's estimated motion between two lidar revolutions, as the companion's SLAM
//! takes it for its motion guess: the simulator's flight part hands its estimate over in
//! process, a real autopilot's comes back over MAVLink (`plumbline companion`); both go
//! through this one rule.
//!
//! Along a featureless corridor the scan match sees nothing along the axis and keeps the
//! guess there. The SLAM's own guess is the previous revolution's motion carried on, which runs
//! on through a stop or a reversal: metres within a few seconds, a map drifted for good. The
//! flight part's estimate follows the IMU along that axis, and it fuses no pose fix along it
//! (the fix is sent as unobserved there), so the two do not feed on each other.

use plumbline_core::geom::Pose2;
use plumbline_core::msgs::EstimatedState;

/// Remembers the flight part's pose at the previous revolution.
#[derive(Clone, Copy, Debug, Default)]
pub struct EstimatedMotion {
    last: Option<Pose2>,
}

impl EstimatedMotion {
    /// The motion since the previous call, in the frame of the pose then (what the SLAM takes
    /// as its prior); `None` for the first call and whenever either estimate was not valid, so
    /// a guess never spans a gap the flight part could not follow.
    pub fn since_last(&mut self, estimate: &EstimatedState) -> Option<Pose2> {
        let now = estimate.valid.then(|| {
            let [x, y, _] = estimate.position_m;
            Pose2::new(x, y, estimate.yaw_rad)
        });
        let motion = self.last.zip(now).map(|(then, now)| then.between(now));
        self.last = now;
        motion
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f32, y: f32, yaw_rad: f32, valid: bool) -> EstimatedState {
        EstimatedState {
            position_m: [x, y, 1.0],
            yaw_rad,
            valid,
            ..EstimatedState::default()
        }
    }

    #[test]
    fn a_reversal_is_the_motion_guessed_not_the_last_motion_carried_on() {
        // Heading along a corridor at 90 degrees: forward 0.1 m, then back 0.05 m.
        let yaw = core::f32::consts::FRAC_PI_2;
        let mut m = EstimatedMotion::default();
        assert_eq!(m.since_last(&at(0.0, 0.0, yaw, true)), None);
        let forward = m.since_last(&at(0.0, 0.1, yaw, true)).unwrap();
        assert!(
            (forward.x - 0.1).abs() < 1e-6 && forward.y.abs() < 1e-6,
            "{forward:?}"
        );
        let back = m.since_last(&at(0.0, 0.05, yaw, true)).unwrap();
        assert!(
            (back.x + 0.05).abs() < 1e-6 && back.y.abs() < 1e-6,
            "{back:?}"
        );
        assert!(back.theta.abs() < 1e-6);
    }

    #[test]
    fn an_invalid_estimate_guesses_nothing_and_is_not_bridged() {
        let mut m = EstimatedMotion::default();
        m.since_last(&at(0.0, 0.0, 0.0, true));
        assert_eq!(m.since_last(&at(5.0, 0.0, 0.0, false)), None);
        // Valid again: the step from the invalid estimate, and the one over the gap, are unknown.
        assert_eq!(m.since_last(&at(0.2, 0.0, 0.0, true)), None);
        let step = m.since_last(&at(0.3, 0.0, 0.0, true)).unwrap();
        assert!((step.x - 0.1).abs() < 1e-6, "{step:?}");
    }
}
