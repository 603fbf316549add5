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
use crate::matching::{LidarOdometry, MotionLimits, OdometryConfig, OdometryStep};
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
    /// The estimate when the previous scan arrived, before and after its match was fused: the
    /// IMU-aided motion since then is the matcher's initial guess, better than repeating the
    /// last motion when a push or a gust changes the velocity between revolutions.
    last_scan: Option<LastScan>,
    /// The levelled copy of the scan being matched.
    leveller: Leveller<N>,
}

impl<const N: usize> Onboard<N> {
    pub fn new(odometry: OdometryConfig, autopilot: AutopilotConfig) -> Self {
        Self {
            odometry: LidarOdometry::new(odometry),
            autopilot: Autopilot::new(autopilot),
            rejected_points: 0,
            last_scan: None,
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
        let out = self.autopilot.step(inputs, dt);
        if let (Some(last), Some(_)) = (self.last_scan.as_mut(), scan) {
            // Taken back one step along the velocity, to the time the next scan's pose is read
            // at (the estimate before its step), so that only the fuse separates it from
            // `before`.
            let e = out.estimate;
            let [vx, vy, _] = e.velocity_m_s;
            last.after = Pose2::new(
                e.position_m[0] - vx * dt,
                e.position_m[1] - vy * dt,
                e.yaw_rad,
            );
        }
        out
    }

    /// Levels the scan, matches it and returns the estimator's view of the odometry step.
    fn match_scan(&mut self, inputs: &Inputs, scan: &Scan<N>) -> ScanMatchDelta {
        let e = self.autopilot.last_outputs().estimate;
        let pose = Pose2::new(e.position_m[0], e.position_m[1], e.yaw_rad);
        let prior = self.last_scan.map(|last| last.prior(pose, scan.stamp_s));
        self.last_scan = Some(LastScan {
            before: pose,
            after: pose,
            stamp_s: scan.stamp_s,
        });
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

/// The estimate at the previous scan, before and after the filter fused what came with it.
#[derive(Clone, Copy, Debug)]
struct LastScan {
    before: Pose2,
    after: Pose2,
    stamp_s: f64,
}

impl LastScan {
    /// The matcher's guess for the scan at `stamp_s`, the estimate then being `now`: the
    /// estimated motion since the previous scan, with the filter's correction at that scan
    /// counted as motion only while the vehicle could have made it in the interval
    /// ([`MotionLimits`]).
    ///
    /// A correction of a few centimetres is mostly the filter catching up with motion its
    /// prediction missed, and the next revolution moves the same way. A larger one is a
    /// position fix (the companion's map, or a match across a corridor that the covariance
    /// carried along it), not motion: replayed as motion, the matcher looks for the wall ends
    /// of a blank corridor that far along it, finds some, and confirms the correction with a
    /// small covariance, so that the next one is larger (an Intel flight ran 1.3 m to 7 m off
    /// in 2 s). Past the reach the guess is the motion since the corrected estimate.
    fn prior(&self, now: Pose2, stamp_s: f64) -> Pose2 {
        let correction = self.before.between(self.after);
        let shift_m = correction.translation().norm();
        let turn_rad = libm::fabsf(correction.theta);
        let dt_s = (stamp_s - self.stamp_s) as f32;
        if MotionLimits::default().allows(shift_m, turn_rad, dt_s) {
            self.before.between(now)
        } else {
            self.after.between(now)
        }
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
    fn a_correction_beyond_the_vehicles_reach_is_not_replayed_as_motion() {
        // The previous scan came 0.25 s ago; since then the estimate moved 0.1 m along x.
        let at = |x: f32| Pose2::new(x, 0.0, 0.0);
        let last = |corrected_m: f32| LastScan {
            before: at(1.0),
            after: at(1.0 + corrected_m),
            stamp_s: 10.0,
        };
        let guess = |corrected_m: f32| last(corrected_m).prior(at(1.1 + corrected_m), 10.25);
        // A few centimetres: the filter catching up with motion its prediction missed, which
        // the next revolution repeats.
        assert!((guess(0.04).x - 0.14).abs() < 1e-5, "{:?}", guess(0.04));
        // Half a metre (a map fix, a correction carried along a corridor) is not motion the
        // vehicle made in a quarter of a second: the guess is the motion since it.
        assert!((guess(0.5).x - 0.1).abs() < 1e-5, "{:?}", guess(0.5));
        assert!((guess(-0.5).x - 0.1).abs() < 1e-5, "{:?}", guess(-0.5));
        // A turn the vehicle cannot make in the interval either.
        let turned = LastScan {
            after: Pose2::new(1.0, 0.0, 0.8),
            ..last(0.0)
        };
        let now = Pose2::new(1.1, 0.0, 0.8);
        assert!(turned.prior(now, 10.25).theta.abs() < 1e-5);
    }

    #[test]
    fn onboard_stack_size_is_known() {
        let size = core::mem::size_of::<Onboard<360>>();
        std::println!("size_of::<Onboard<360>>() = {size} bytes");
        assert!(size < 256 * 1024, "{size}");
    }
}
