//! Tests of [`super`], kept apart so the module itself stays short.

extern crate std;
use super::*;
use crate::geom::Pose2;
use crate::msgs::{ScanMatchStatus, GRAVITY_M_S2};
use nalgebra::{Matrix4, Vector4};

/// Deterministic normal samples for the tests (xorshift64* and Box-Muller).
pub(super) struct Gauss(pub(super) u64);

impl Gauss {
    fn uniform(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
        (bits as f32 + 0.5) / (1u64 << 24) as f32
    }

    pub(super) fn normal(&mut self, sigma: f32) -> f32 {
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
fn refused_scan_matches_reopen_the_filter_within_the_lidar_timeout() {
    use crate::flight::supervisor::SupervisorConfig;
    let mut rng = Gauss(7);
    let mut est = Estimator::new(EstimatorConfig::default());
    let level = level_at_rest();
    let origin = Pose2::new(0.0, 0.0, 0.0);
    let reference = ScanMatchDelta {
        status: ScanMatchStatus::ReferenceOnly,
        ..scan(&mut rng, 0.0, origin, origin)
    };
    assert_eq!(est.fuse_scan_match(&reference, 0.0), Outcome::Accepted);
    // The filter believes it hovers at the origin; every revolution (4 Hz, the XV-11's) says
    // the vehicle is 1 m along x: far outside the gate, and right.
    let moved = Pose2::new(1.0, 0.0, 0.0);
    let period_s = 0.25;
    let mut accepted_at_s = None;
    for k in 1..=8 {
        for _ in 0..125 {
            assert!(est.predict(&level, 0.002));
        }
        let t_s = k as f64 * period_s;
        let m = ScanMatchDelta {
            becomes_reference: false,
            ..scan(&mut rng, t_s, moved, origin)
        };
        if est.fuse_scan_match(&m, 0.0) == Outcome::Accepted {
            accepted_at_s = Some(t_s);
            break;
        }
    }
    // Refused at 0.25 and 0.5 s; the refusal at 0.75 s ends a run of 0.5 s, the filter is
    // reopened and that match used at once: before the supervisor would call the lidar lost.
    let accepted_at_s = accepted_at_s.expect("never reopened");
    let c = est.config.ekf;
    assert!((accepted_at_s - 0.25 - f64::from(c.scan_reopen_after_s)).abs() < 1e-9);
    assert!((accepted_at_s as f32) < SupervisorConfig::default().lidar_timeout_s);
    let counted = est.counters().scan_match;
    assert_eq!(
        (counted.rejected, counted.resets, counted.accepted),
        (3, 1, 2)
    );
    assert!(
        (est.state().position_m[0] - 1.0).abs() < 0.05,
        "{:?}",
        est.state()
    );
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
