//! The estimator the autopilot owns: tilt filter plus EKF, with fault counters per input.
//!
//! A thin wrapper (DESIGN.md §2): it turns raw messages into the filters' inputs, counts every
//! sample it could not use, and reports the estimate in the message type the controllers read.

use super::at_rest::AtRestConfig;
use super::attitude::{AttitudeConfig, AttitudeFilter};
use super::drag::{DragConfig, DragWindow};
use super::ekf::{ix, Counters, Ekf, EkfConfig, Outcome};
use super::imu::ImuStep;
use super::pose_fix::{CompanionFrame, FixOutcome, PoseFixConfig};
use super::sonar::SonarConfig;
use super::validity::Horizontal;
use crate::msgs::{EstimatedState, ImuSample, PoseFix, ScanMatchDelta, SonarSample};
use libm::sqrtf;

/// Settings of every part of the estimator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatorConfig {
    pub attitude: AttitudeConfig,
    pub ekf: EkfConfig,
    pub sonar: SonarConfig,
    pub at_rest: AtRestConfig,
    pub drag: DragConfig,
    pub pose_fix: PoseFixConfig,
}

/// What happened to the inputs so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EstimatorCounters {
    /// IMU samples refused (non-finite values or a bad `dt`).
    pub imu_faults: u32,
    pub scan_match: Counters,
    pub sonar: Counters,
    pub at_rest: Counters,
    pub drag: Counters,
}

/// What the autopilot knows about the vehicle that the sensors do not say. These facts decide
/// which of the estimator's assumed measurements hold: "still on the floor" and rotor drag.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Situation {
    /// Disarmed: the vehicle stands on the floor.
    pub disarmed: bool,
    /// In a mode whose rotors carry the vehicle (takeoff, hold, land, manual).
    pub rotors_carry: bool,
    /// The supervisor has declared the lidar lost.
    pub lidar_lost: bool,
    /// Below this estimated height (m) the vehicle counts as on the ground.
    pub ground_height_m: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimator {
    pub config: EstimatorConfig,
    attitude: AttitudeFilter,
    ekf: Ekf,
    drag_window: DragWindow,
    counters: EstimatorCounters,
    /// The companion's map frame and its pose-fix tallies.
    companion: CompanionFrame,
    /// Time predicted since "at rest" was last fused (s).
    since_at_rest_s: f32,
    /// Stamp of the first scan match of the current run of refusals (s).
    scan_refused_since_s: Option<f64>,
}

impl Estimator {
    pub fn new(config: EstimatorConfig) -> Self {
        Self {
            config,
            attitude: AttitudeFilter::new(config.attitude),
            ekf: Ekf::new(config.ekf),
            drag_window: DragWindow::default(),
            counters: EstimatorCounters::default(),
            companion: CompanionFrame::default(),
            since_at_rest_s: f32::INFINITY,
            scan_refused_since_s: None,
        }
    }

    pub fn counters(&self) -> &EstimatorCounters {
        &self.counters
    }

    pub fn ekf(&self) -> &Ekf {
        &self.ekf
    }

    /// Body rates with the tilt filter's bias removed on x and y and the EKF's on z (rad/s).
    pub fn body_rates(&self, gyro_rad_s: [f32; 3]) -> [f32; 3] {
        let mut w = self.attitude.corrected_rate(gyro_rad_s);
        w[2] = gyro_rad_s[2] - self.ekf.state()[ix::GYRO_Z_BIAS];
        w
    }

    /// Tilt filter then EKF prediction. Returns false (and counts it) if the sample was refused.
    pub fn predict(&mut self, imu: &ImuSample, dt: f32) -> bool {
        // The tilt filter's gravity reference is the specific force with the EKF's accelerometer
        // bias removed, the same force the EKF predicts with: fed the raw reading, the tilt
        // filter would pull toward a tilt the EKF keeps correcting away, and once the lidar
        // stops the two would disagree on which way is level.
        let bias = self.ekf.state().fixed_rows::<3>(ix::ACCEL_BIAS);
        let accel: [f32; 3] = core::array::from_fn(|i| imu.accel_m_s2[i] - bias[i]);
        if self.attitude.update(imu.gyro_rad_s, accel, dt).is_err() {
            self.counters.imu_faults = self.counters.imu_faults.saturating_add(1);
            return false;
        }
        let mut gyro = self.attitude.corrected_rate(imu.gyro_rad_s);
        gyro[2] = imu.gyro_rad_s[2];
        let step = ImuStep {
            accel_m_s2: imu.accel_m_s2,
            gyro_rad_s: gyro,
            tilt: *self.attitude.tilt(),
        };
        let ok = self.ekf.predict(&step, dt).is_ok();
        if ok {
            self.drag_window.add(imu.accel_m_s2, dt);
            self.since_at_rest_s += dt;
        } else {
            self.counters.imu_faults = self.counters.imu_faults.saturating_add(1);
        }
        ok
    }

    /// Fuses the measurements that follow from the vehicle's situation rather than from a
    /// sensor: "at rest" while it stands on the floor, the drag reading while it flies.
    pub fn fuse_situation(&mut self, s: &Situation) {
        // Disarmed means on the floor; so does an estimate below the floor, which happens when a
        // touchdown stops the vehicle below the sonar's minimum range and the IMU missed the
        // shock: it is still and at height zero.
        if s.disarmed || self.ekf.state()[ix::POS + 2] < 0.0 {
            self.fuse_at_rest();
        }
        // The drag measurement holds only in the air (on the floor the accelerometer feels the
        // floor's slope and friction), and after a lidar loss only if configured to: a draught
        // then reads as ground velocity (`DragConfig::without_lidar`).
        let flying = s.rotors_carry && self.ekf.state()[ix::POS + 2] > s.ground_height_m;
        self.fuse_drag(flying && (!s.lidar_lost || self.config.drag.without_lidar));
    }

    /// Fuses the accelerometer's drag reading once a window is full, if the vehicle has been
    /// `flying` on its rotors the whole window; otherwise the window is dropped. Rejections (a push, a
    /// collision) are counted and never reopen anything: the lidar, not this, is the position
    /// reference.
    fn fuse_drag(&mut self, flying: bool) -> Option<Outcome> {
        if !flying {
            self.drag_window.clear();
            return None;
        }
        let mean = self.drag_window.take(self.config.drag.window_s)?;
        let outcome = self
            .ekf
            .fuse_drag(&self.config.drag, mean, self.attitude.tilt());
        self.counters.drag.record(outcome);
        self.feed_back_tilt();
        Some(outcome)
    }

    /// Fuses a scan-matcher result whose pose belongs `latency_s` before now; after a run of
    /// rejections (`EkfConfig::scan_reopen_after_s` long, or `reset_after_rejections` of them,
    /// whichever ends first) the horizontal pose and velocity are reopened so the matcher can
    /// pull the filter back (a pose jump after an outage, an estimate that slid).
    pub fn fuse_scan_match(&mut self, m: &ScanMatchDelta, latency_s: f32) -> Outcome {
        // The match refers to the reference it may replace: to use it at once after a reopen,
        // the filter goes back to before it.
        let before = self.ekf;
        let mut outcome = self.ekf.fuse_scan_match(m, latency_s);
        if self.scan_refusals_ran_out(outcome, m.t_s) {
            self.ekf = before;
            let [sp, _, sv, sy] = self.config.ekf.reopen_std;
            self.ekf.reset_variance(&[
                (ix::POS, sp * sp),
                (ix::POS + 1, sp * sp),
                (ix::VEL, sv * sv),
                (ix::VEL + 1, sv * sv),
                (ix::YAW, sy * sy),
            ]);
            outcome = self.ekf.fuse_scan_match(m, latency_s);
            self.counters.scan_match.record(outcome);
        }
        self.feed_back_tilt();
        outcome
    }

    /// Records a scan-match outcome stamped `t_s`; true when it ends a run of refusals long
    /// enough to reopen the filter (the run is then counted as a reset). The count backs the
    /// time up for stamps that do not advance.
    fn scan_refusals_ran_out(&mut self, outcome: Outcome, t_s: f64) -> bool {
        let c = &self.config.ekf;
        let counted = self
            .counters
            .scan_match
            .record_gated(outcome, c.reset_after_rejections);
        let timed = match outcome {
            Outcome::Accepted => false,
            Outcome::Rejected => {
                let first = *self.scan_refused_since_s.get_or_insert(t_s);
                (t_s - first) as f32 >= c.scan_reopen_after_s
                    && self.counters.scan_match.record_gated_now()
            }
            Outcome::Invalid => return false,
        };
        if outcome == Outcome::Accepted || counted || timed {
            self.scan_refused_since_s = None;
        }
        counted || timed
    }

    /// Fuses a companion pose fix that arrived `age_s` after its time ([`super::pose_fix`]).
    pub fn fuse_pose_fix(&mut self, fix: &PoseFix, age_s: f32) -> FixOutcome {
        let c = self.config.pose_fix;
        let outcome = self.companion.fuse(&mut self.ekf, &c, fix, age_s);
        self.feed_back_tilt();
        outcome
    }

    /// The companion's map frame: its anchor in the world frame and the pose-fix tallies.
    pub fn companion_frame(&self) -> &CompanionFrame {
        &self.companion
    }

    /// Fuses a sonar range; after a run of rejections the height, climb rate and vertical
    /// accelerometer bias are reopened and this range is used at once (a touchdown shock the
    /// accelerometer did not report leaves the filter believing it still descends).
    pub fn fuse_sonar(&mut self, s: &SonarSample) -> Outcome {
        let (roll, pitch) = self.attitude.roll_pitch();
        let sonar = self.config.sonar;
        let mut outcome = self.ekf.fuse_sonar(&sonar, s.range_m, roll, pitch);
        let limit = self.config.ekf.reset_after_rejections;
        if self.counters.sonar.record_gated(outcome, limit) {
            let [_, sh, sv, _] = self.config.ekf.reopen_std;
            let bias_std = self.config.ekf.initial_bias_std[0];
            self.ekf.reset_variance(&[
                (ix::POS + 2, sh * sh),
                (ix::VEL + 2, sv * sv),
                (ix::ACCEL_BIAS + 2, bias_std * bias_std),
            ]);
            outcome = self.ekf.fuse_sonar(&sonar, s.range_m, roll, pitch);
            self.counters.sonar.record(outcome);
        }
        self.feed_back_tilt();
        outcome
    }

    /// Fuses "still on the floor", which the situation says is a fact, once `at_rest.period_s` of prediction has passed since it last did
    /// (`None` until then): a rejection means the filter is wrong, so velocity and height are
    /// reopened at once and the fact applied.
    fn fuse_at_rest(&mut self) -> Option<Outcome> {
        // A microsecond of slack, so rounding in the sum of steps does not skip a period.
        if self.since_at_rest_s + 1e-6 < self.config.at_rest.period_s {
            return None;
        }
        self.since_at_rest_s = 0.0;
        let mut outcome = self.ekf.fuse_at_rest(&self.config.at_rest);
        if self.counters.at_rest.record_gated(outcome, 1) {
            let [_, sh, sv, _] = self.config.ekf.reopen_std;
            self.ekf.reset_variance(&[
                (ix::POS + 2, sh * sh),
                (ix::VEL, sv * sv),
                (ix::VEL + 1, sv * sv),
                (ix::VEL + 2, sv * sv),
            ]);
            outcome = self.ekf.fuse_at_rest(&self.config.at_rest);
            self.counters.at_rest.record(outcome);
        }
        self.feed_back_tilt();
        Some(outcome)
    }

    /// Moves the EKF's tilt and gyro-bias error estimates into the tilt filter (error-state
    /// reset).
    fn feed_back_tilt(&mut self) {
        let heading = self.ekf.state()[ix::YAW];
        let (tilt, gyro_bias) = self.ekf.take_tilt_error();
        // A rejected or unrelated measurement leaves nothing to apply.
        if tilt != [0.0; 2] {
            self.attitude.correct_tilt(tilt, heading);
        }
        if gyro_bias != [0.0; 2] {
            self.attitude.correct_bias(gyro_bias);
        }
    }

    /// What the horizontal estimate still knows, axis by axis ([`super::validity`]).
    pub fn horizontal(&self) -> Horizontal {
        self.ekf.horizontal()
    }

    /// The estimate as the controllers and the log see it.
    pub fn state(&self) -> EstimatedState {
        let x = self.ekf.state();
        let p = self.ekf.covariance();
        let (roll_rad, pitch_rad) = self.attitude.roll_pitch();
        EstimatedState {
            position_m: [x[ix::POS], x[ix::POS + 1], x[ix::POS + 2]],
            velocity_m_s: [x[ix::VEL], x[ix::VEL + 1], x[ix::VEL + 2]],
            roll_rad,
            pitch_rad,
            yaw_rad: x[ix::YAW],
            position_std_m: core::array::from_fn(|i| sqrtf(p[(ix::POS + i, ix::POS + i)].max(0.0))),
            valid: self.ekf.is_valid(),
        }
    }
}

#[cfg(test)]
#[path = "estimator_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "corridor_tests.rs"]
mod corridor_tests;
