//! The estimator the autopilot owns: tilt filter plus EKF, with fault counters per input.
//!
//! A thin wrapper (DESIGN.md §2): it turns raw messages into the filters' inputs, counts every
//! sample it could not use, and reports the estimate in the message type the controllers read.

use super::at_rest::AtRestConfig;
use super::attitude::{AttitudeConfig, AttitudeFilter};
use super::drag::{DragConfig, DragWindow};
use super::ekf::{ix, Counters, Ekf, EkfConfig, Outcome};
use super::imu::ImuStep;
use super::sonar::SonarConfig;
use crate::msgs::{EstimatedState, ImuSample, ScanMatchDelta, SonarSample};
use libm::sqrtf;

/// Settings of every part of the estimator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatorConfig {
    pub attitude: AttitudeConfig,
    pub ekf: EkfConfig,
    pub sonar: SonarConfig,
    pub at_rest: AtRestConfig,
    pub drag: DragConfig,
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
    /// Time predicted since "at rest" was last fused (s).
    since_at_rest_s: f32,
}

impl Estimator {
    pub fn new(config: EstimatorConfig) -> Self {
        Self {
            config,
            attitude: AttitudeFilter::new(config.attitude),
            ekf: Ekf::new(config.ekf),
            drag_window: DragWindow::default(),
            counters: EstimatorCounters::default(),
            since_at_rest_s: f32::INFINITY,
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
    /// rejections the horizontal pose and velocity are reopened so the matcher can pull the
    /// filter back (a pose jump after an outage).
    pub fn fuse_scan_match(&mut self, m: &ScanMatchDelta, latency_s: f32) -> Outcome {
        let outcome = self.ekf.fuse_scan_match(m, latency_s);
        let limit = self.config.ekf.reset_after_rejections;
        if self.counters.scan_match.record_gated(outcome, limit) {
            let [sp, _, sv, sy] = self.config.ekf.reopen_std;
            self.ekf.reset_variance(&[
                (ix::POS, sp * sp),
                (ix::POS + 1, sp * sp),
                (ix::VEL, sv * sv),
                (ix::VEL + 1, sv * sv),
                (ix::YAW, sy * sy),
            ]);
        }
        self.feed_back_tilt();
        outcome
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
mod tests {
    extern crate std;
    use super::*;
    use crate::geom::Pose2;
    use crate::msgs::{ScanMatchStatus, GRAVITY_M_S2};
    use nalgebra::{Matrix4, Vector4};

    /// Deterministic normal samples for the tests (xorshift64* and Box-Muller).
    struct Gauss(u64);

    impl Gauss {
        fn uniform(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
            (bits as f32 + 0.5) / (1u64 << 24) as f32
        }

        fn normal(&mut self, sigma: f32) -> f32 {
            let (u1, u2) = (self.uniform(), self.uniform());
            sigma * sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(2.0 * core::f32::consts::PI * u2)
        }
    }

    const IMU_HZ: f32 = 500.0;
    const ACCEL_SIGMA: f32 = 0.2;
    const GYRO_SIGMA: f32 = 0.005;
    const SCAN_SIGMA_M: f32 = 0.01;
    const SCAN_SIGMA_RAD: f32 = 0.005;

    /// Noise settings matching the simulated sensors below.
    fn matched_config() -> EstimatorConfig {
        let root = sqrtf(IMU_HZ);
        EstimatorConfig {
            ekf: EkfConfig {
                initial_std: [0.05, 0.3, 0.05],
                // The simulated matcher below reports its true covariance.
                scan_covariance_scale: 1.0,
                accel_noise_density: ACCEL_SIGMA / root,
                gyro_noise_density: GYRO_SIGMA / root,
                ..EkfConfig::default()
            },
            ..EstimatorConfig::default()
        }
    }

    fn scan(rng: &mut Gauss, t_s: f64, truth: Pose2, reference: Pose2) -> ScanMatchDelta {
        let d = reference.between(truth);
        let (sm, sr) = (SCAN_SIGMA_M * SCAN_SIGMA_M, SCAN_SIGMA_RAD * SCAN_SIGMA_RAD);
        ScanMatchDelta {
            t_s,
            status: ScanMatchStatus::Matched,
            dx_m: d.x + rng.normal(SCAN_SIGMA_M),
            dy_m: d.y + rng.normal(SCAN_SIGMA_M),
            dtheta_rad: d.theta + rng.normal(SCAN_SIGMA_RAD),
            covariance: [[sm, 0.0, 0.0], [0.0, sm, 0.0], [0.0, 0.0, sr]],
            degenerate_axis: None,
            becomes_reference: true,
        }
    }

    /// Flies a constant-velocity, constant-heading truth for 20 s with scan-to-scan matches at
    /// 5 Hz; returns the final NEES over (x, y, vx, vy) and the final velocity error and sigma.
    fn run(seed: u64) -> (f32, f32, f32) {
        let mut rng = Gauss(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
        let mut est = Estimator::new(matched_config());
        let (vx, vy, yaw) = (0.2f32, -0.1f32, 0.0f32);
        let dt = 1.0 / IMU_HZ;
        let mut reference = Pose2::new(0.0, 0.0, yaw);
        est.fuse_scan_match(
            &ScanMatchDelta {
                status: ScanMatchStatus::ReferenceOnly,
                ..scan(&mut rng, 0.0, reference, reference)
            },
            0.0,
        );
        let steps = (20.0 * IMU_HZ) as usize;
        let mut truth = reference;
        for k in 1..=steps {
            let t = k as f32 * dt;
            truth = Pose2::new(vx * t, vy * t, yaw);
            let imu = ImuSample {
                t_s: t as f64,
                gyro_rad_s: core::array::from_fn(|_| rng.normal(GYRO_SIGMA)),
                accel_m_s2: [
                    rng.normal(ACCEL_SIGMA),
                    rng.normal(ACCEL_SIGMA),
                    GRAVITY_M_S2 + rng.normal(ACCEL_SIGMA),
                ],
            };
            assert!(est.predict(&imu, dt));
            if k % 100 == 0 {
                let m = scan(&mut rng, t as f64, truth, reference);
                est.fuse_scan_match(&m, 0.0);
                reference = truth;
            }
        }
        let x = est.ekf().state();
        let p = est.ekf().covariance();
        let idx = [ix::POS, ix::POS + 1, ix::VEL, ix::VEL + 1];
        let e = Vector4::new(
            x[idx[0]] - truth.x,
            x[idx[1]] - truth.y,
            x[idx[2]] - vx,
            x[idx[3]] - vy,
        );
        let sub = Matrix4::from_fn(|i, j| p[(idx[i], idx[j])]);
        let nees = e.dot(&(sub.try_inverse().unwrap() * e));
        (
            nees,
            libm::hypotf(e[2], e[3]),
            sqrtf(sub[(2, 2)] + sub[(3, 3)]),
        )
    }

    #[test]
    fn constant_velocity_truth_converges_with_a_consistent_covariance() {
        let seeds = 20;
        let mut nees_sum = 0.0;
        for seed in 0..seeds {
            let (nees, v_err, v_sigma) = run(seed);
            assert!(
                v_err < 0.1 && v_err < 4.0 * v_sigma,
                "seed {seed}: {v_err} vs {v_sigma}"
            );
            assert!(v_sigma < 0.05, "seed {seed}: velocity sigma {v_sigma}");
            nees_sum += nees;
        }
        let mean = nees_sum / seeds as f32;
        std::println!("mean NEES over {seeds} runs: {mean}");
        // Four degrees of freedom: a consistent filter averages 4 (95 % band over 20 runs about
        // 2.9..5.3); a wide band still catches an over- or under-confident filter.
        assert!((2.0..8.0).contains(&mean), "mean NEES {mean}");
    }

    /// What the IMU of a level vehicle standing still reads.
    fn level_at_rest() -> ImuSample {
        ImuSample {
            accel_m_s2: [0.0, 0.0, GRAVITY_M_S2],
            ..ImuSample::default()
        }
    }

    #[test]
    fn a_run_of_sonar_rejections_reopens_the_height() {
        let mut est = Estimator::new(EstimatorConfig::default());
        let level = level_at_rest();
        // The filter thinks it is on the floor; the sonar insists on 1.5 m.
        for k in 0..20 {
            assert!(est.predict(&level, 0.002));
            let outcome = est.fuse_sonar(&SonarSample {
                t_s: 0.0,
                range_m: 1.5,
            });
            if k < 9 {
                assert_eq!(outcome, Outcome::Rejected);
            }
        }
        let c = est.counters().sonar;
        assert_eq!((c.rejected, c.resets), (10, 1));
        assert!((est.state().position_m[2] - 1.5).abs() < 0.05);
    }

    #[test]
    fn at_rest_is_fused_once_a_period() {
        let mut est = Estimator::new(EstimatorConfig::default());
        let level = level_at_rest();
        let mut fused = 0;
        for _ in 0..50 {
            assert!(est.predict(&level, 0.002));
            fused += usize::from(est.fuse_at_rest().is_some());
        }
        // 0.1 s at 500 Hz: the first step, then every 10 ms.
        assert_eq!(fused, 10);
        assert_eq!(est.counters().at_rest.accepted, 10);
    }

    /// One second standing level (or hovering level at 1 m by the sonar) in `situation`,
    /// with `config`; returns how often at-rest and drag were fused.
    fn fusions(situation: Situation, config: EstimatorConfig, sonar_m: Option<f32>) -> (u32, u32) {
        let mut est = Estimator::new(config);
        for _ in 0..500 {
            assert!(est.predict(&level_at_rest(), 0.002));
            if let Some(range_m) = sonar_m {
                est.fuse_sonar(&SonarSample { t_s: 0.0, range_m });
            }
            est.fuse_situation(&situation);
        }
        let total = |c: Counters| c.accepted + c.rejected + c.invalid;
        let c = est.counters();
        (total(c.at_rest), total(c.drag))
    }

    #[test]
    fn the_situation_decides_between_at_rest_and_drag() {
        let config = EstimatorConfig::default();
        let on_floor = Situation {
            disarmed: true,
            rotors_carry: false,
            lidar_lost: false,
            ground_height_m: 0.05,
        };
        let (at_rest, drag) = fusions(on_floor, config, None);
        assert!(at_rest >= 90 && drag == 0, "{at_rest} {drag}");

        let flying = Situation {
            disarmed: false,
            rotors_carry: true,
            ..on_floor
        };
        let (at_rest, drag) = fusions(flying, config, Some(1.0));
        assert!(at_rest == 0 && drag >= 5, "{at_rest} {drag}");
        // Spinning up on the floor is not flying.
        assert_eq!(fusions(flying, config, None), (0, 0));

        let lidar_lost = Situation {
            lidar_lost: true,
            ..flying
        };
        assert_eq!(fusions(lidar_lost, config, Some(1.0)).1, 0);
        let mut without_lidar = config;
        without_lidar.drag.without_lidar = true;
        assert!(fusions(lidar_lost, without_lidar, Some(1.0)).1 >= 5);
    }

    #[test]
    fn refused_samples_are_counted_and_the_estimate_stays_finite() {
        let mut est = Estimator::new(EstimatorConfig::default());
        let bad = ImuSample {
            gyro_rad_s: [f32::NAN, 0.0, 0.0],
            ..ImuSample::default()
        };
        assert!(!est.predict(&bad, 0.002));
        assert!(!est.predict(&ImuSample::default(), f32::NAN));
        assert_eq!(est.counters().imu_faults, 2);
        est.fuse_sonar(&SonarSample {
            t_s: 0.0,
            range_m: f32::INFINITY,
        });
        assert_eq!(est.counters().sonar.invalid, 1);
        let s = est.state();
        assert!(s.valid && s.position_m.iter().all(|v| v.is_finite()));
    }
}
