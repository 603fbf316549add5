//! The onboard stack: keyframe lidar odometry feeding the autopilot.
//!
//! Seed 000 Fig. 8: the lidar's revolutions go through the scan matcher, whose displacement
//! (Δx, Δy against the reference scan) drives the position hold. [`Onboard`] owns the
//! [`LidarOdometry`] and the [`Autopilot`]; a driver hands it the sensor inputs and, when a
//! revolution completes, the scan. The translation from the odometry's step to the estimator's
//! [`ScanMatchDelta`] is [`scan_match_delta`].

use super::autopilot::{Autopilot, AutopilotConfig};
use super::params::ParamError;
use crate::geom::Pose2;
use crate::guidance::nearest_hits::NearestHits;
use crate::matching::{LidarOdometry, OdometryConfig, OdometryStep};
use crate::msgs::{EstimatedState, Inputs, Outputs, ScanMatchDelta, ScanMatchStatus};
use crate::scan::level::{Leveller, ScanPlane};
use crate::scan::sweep::SweepMotion;
use crate::scan::Scan;

/// Lidar odometry plus autopilot, for scans of up to `N` beams.
#[derive(Clone, Debug)]
pub struct Onboard<const N: usize> {
    odometry: LidarOdometry<N>,
    autopilot: Autopilot,
    /// Scan points the matcher's dynamic-object test has rejected so far (seed 000 sec. 4.2).
    rejected_points: u64,
    /// The estimated pose when the previous scan arrived: the IMU-aided motion since then is
    /// the matcher's initial guess, better than repeating the last motion when a push or a
    /// gust changes the velocity between revolutions.
    pose_at_last_scan: Option<Pose2>,
    /// The levelled copy of the scan being matched.
    leveller: Leveller<N>,
}

impl<const N: usize> Onboard<N> {
    pub fn new(odometry: OdometryConfig, autopilot: AutopilotConfig) -> Self {
        Self {
            odometry: LidarOdometry::new(odometry),
            autopilot: Autopilot::new(autopilot),
            rejected_points: 0,
            pose_at_last_scan: None,
            leveller: Leveller::default(),
        }
    }

    pub fn autopilot(&self) -> &Autopilot {
        &self.autopilot
    }

    /// The autopilot, for setting its parameters between steps.
    pub fn autopilot_mut(&mut self) -> &mut Autopilot {
        &mut self.autopilot
    }

    /// Sets a tuning parameter of the autopilot (see [`Autopilot::set_param`]).
    pub fn set_param(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        self.autopilot.set_param(index, value)
    }

    pub fn rejected_points(&self) -> u64 {
        self.rejected_points
    }

    /// One step: match the scan if one completed, hand its nearest hits to the autopilot's
    /// setpoint guard, then run the autopilot. A scan-match result already in `inputs` is
    /// replaced when a scan is given.
    pub fn step(&mut self, inputs: &Inputs, scan: Option<&Scan<N>>, dt: f32) -> Outputs {
        // The inputs are copied (a library call each step) only when a scan's match goes in.
        let matched;
        let inputs = match scan {
            Some(scan) => {
                self.autopilot.observe_hits(NearestHits::of_scan(scan));
                matched = Inputs {
                    scan_match: Some(self.match_scan(inputs, scan)),
                    ..*inputs
                };
                &matched
            }
            None => inputs,
        };
        self.autopilot.step(inputs, dt)
    }

    /// Levels the scan, matches it and returns the estimator's view of the odometry step.
    fn match_scan(&mut self, inputs: &Inputs, scan: &Scan<N>) -> ScanMatchDelta {
        let e = self.autopilot.last_outputs().estimate;
        let pose = Pose2::new(e.position_m[0], e.position_m[1], e.yaw_rad);
        let prior = self.pose_at_last_scan.map(|before| before.between(pose));
        self.pose_at_last_scan = Some(pose);
        // The height estimate is of the vehicle; the lidar sits a little above it, which only
        // makes the floor test stricter.
        let plane = ScanPlane {
            roll_rad: e.roll_rad,
            pitch_rad: e.pitch_rad,
            height_m: e.position_m[2],
        };
        let level = self.leveller.level(scan, plane, sweep_motion(&e, inputs));
        let step = self.odometry.update(level, prior);
        if let OdometryStep::Matched { result, .. } = &step {
            self.rejected_points += u64::from(result.quality.rejected_dynamic);
        }
        scan_match_delta(&step, scan.stamp_s)
    }
}

/// The motion that smeared the revolution: the estimated velocity turned into the heading
/// frame, and the gyro's yaw rate (its bias, a few mrad/s, moves a beam by well under a
/// millimetre over a revolution).
fn sweep_motion(e: &EstimatedState, inputs: &Inputs) -> SweepMotion {
    let (s, c) = libm::sincosf(e.yaw_rad);
    let [vx, vy, _] = e.velocity_m_s;
    SweepMotion {
        velocity_m_s: [c * vx + s * vy, c * vy - s * vx],
        yaw_rate_rad_s: inputs.imu.gyro_rad_s[2],
    }
}

/// The estimator's view of one odometry step. The odometry matches against keyframes, so the
/// pose change is relative to the current keyframe and the filter re-clones its reference pose
/// exactly when the odometry says it took one.
pub fn scan_match_delta(step: &OdometryStep, t_s: f64) -> ScanMatchDelta {
    let mut delta = ScanMatchDelta {
        t_s,
        status: ScanMatchStatus::Failed,
        dx_m: 0.0,
        dy_m: 0.0,
        dtheta_rad: 0.0,
        covariance: [[0.0; 3]; 3],
        degenerate_axis: None,
        becomes_reference: step.took_keyframe(),
    };
    match step {
        OdometryStep::Started => delta.status = ScanMatchStatus::ReferenceOnly,
        OdometryStep::Matched { result, .. } => {
            delta.status = ScanMatchStatus::Matched;
            delta.dx_m = result.motion.x;
            delta.dy_m = result.motion.y;
            delta.dtheta_rad = result.motion.theta;
            delta.covariance = result.observed_covariance;
            delta.degenerate_axis = result.quality.degenerate_direction.map(|d| [d.x, d.y]);
        }
        OdometryStep::Predicted { .. } => {}
    }
    delta
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::matching::MatchError;

    /// A 360-beam scan of a 6 m x 4 m room (walls at x = -3, 3 and y = -2, 2) taken at `pose`.
    fn room_scan(pose: Pose2, stamp_s: f64) -> Scan<360> {
        let mut scan = Scan::new(stamp_s);
        for k in 0..360 {
            let a = (k as f32).to_radians();
            let (s, c) = libm::sincosf(a + pose.theta);
            let mut r = f32::INFINITY;
            for (d, wall) in [
                (c, 3.0 - pose.x),
                (-c, 3.0 + pose.x),
                (s, 2.0 - pose.y),
                (-s, 2.0 + pose.y),
            ] {
                if d > 1e-6 {
                    r = r.min(wall / d);
                }
            }
            scan.push(crate::scan::Beam::new(a, r)).unwrap();
        }
        scan
    }

    #[test]
    fn odometry_steps_map_onto_the_estimator_message() {
        let mut odometry = LidarOdometry::<360>::new(OdometryConfig::default());
        let first = odometry.update(&room_scan(Pose2::IDENTITY, 0.0), None);
        let started = scan_match_delta(&first, 0.0);
        assert_eq!(started.status, ScanMatchStatus::ReferenceOnly);
        assert!(started.becomes_reference);

        let moved = Pose2::new(0.05, -0.03, 0.02);
        let step = odometry.update(&room_scan(moved, 0.25), None);
        let m = scan_match_delta(&step, 0.25);
        assert_eq!(m.status, ScanMatchStatus::Matched, "{step:?}");
        assert!(
            (m.dx_m - 0.05).abs() < 0.01 && (m.dy_m + 0.03).abs() < 0.01,
            "{m:?}"
        );
        assert!((m.dtheta_rad - 0.02).abs() < 0.005, "{m:?}");
        assert!(m.covariance[0][0] > 0.0 && m.covariance[1][1] > 0.0);
        assert!(!m.becomes_reference && m.t_s == 0.25);

        // A scan the matcher cannot use fails without becoming the keyframe.
        let mut blind_scan = Scan::<360>::new(0.5);
        blind_scan.push(crate::scan::Beam::new(0.0, 1.0)).unwrap();
        let blind = odometry.update(&blind_scan, None);
        assert!(
            matches!(
                blind,
                OdometryStep::Predicted {
                    restarted: false,
                    ..
                }
            ),
            "{blind:?}"
        );
        let f = scan_match_delta(&blind, 0.5);
        assert_eq!(f.status, ScanMatchStatus::Failed);
        assert!(!f.becomes_reference);
        // A failed match that restarted the odometry from its scan re-clones the reference.
        let lost = OdometryStep::Predicted {
            error: MatchError::TooFewCorrespondences {
                found: 3,
                needed: 20,
            },
            restarted: true,
        };
        let restarted = scan_match_delta(&lost, 3.0);
        assert_eq!(restarted.status, ScanMatchStatus::Failed);
        assert!(restarted.becomes_reference);
    }

    #[test]
    fn onboard_stack_size_is_known() {
        let size = core::mem::size_of::<Onboard<360>>();
        std::println!("size_of::<Onboard<360>>() = {size} bytes");
        assert!(size < 256 * 1024, "{size}");
    }
}
