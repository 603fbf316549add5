//! The estimator down a featureless corridor: the scan matches see across it and nothing along
//! it, and the drag the accelerometer feels is all that tells the speed along it.
//!
//! The truth follows the simulator's physics (`crates/sim`, vehicle `f450`, indoor gusts): a
//! vehicle carried down the corridor at a steady ground speed by thrust tilted against linear
//! and quadratic drag on its air-relative velocity, in draughts that are a first-order
//! Gauss-Markov process per horizontal axis; an ADIS16365-class IMU with a bias.

extern crate std;
use super::tests::Gauss;
use super::*;
use crate::estimate::attitude::Tilt;
use crate::msgs::{ScanMatchStatus, GRAVITY_M_S2};
use libm::{asinf, atan2f};

const DT: f32 = 0.002;
/// The F450's drag per unit mass: linear 0.12 N/(m/s) and quadratic 0.05 N/(m/s)^2 on 1.2 kg.
const LINEAR_PER_S: f32 = 0.1;
const QUADRATIC_PER_M: f32 = 0.05 / 1.2;
/// Indoor draughts: 0.3 m/s one-sigma, 2 s correlation time.
const WIND_SIGMA_M_S: f32 = 0.3;
const WIND_TAU_S: f32 = 2.0;
const ACCEL_SIGMA: f32 = 0.02 * 22.36;
const GYRO_SIGMA: f32 = 0.000_768 * 22.36;
const HEIGHT_M: f32 = 1.0;

/// What one corridor flight showed.
struct Flight {
    /// Largest along-axis velocity one-sigma down the corridor (m/s).
    worst_velocity_std: f32,
    /// Along-axis velocity error over its one-sigma at the end, and the one-sigma (m/s).
    end_velocity_error: f32,
    end_velocity_std: f32,
    /// Seconds into the corridor at which the along-axis position one-sigma passed the
    /// degraded bound (None: never within the flight).
    position_lost_s: Option<f32>,
}

/// Hovers `settle_s` with full scan matches, then flies `corridor_s` down a corridor along
/// world x at 0.5 m/s (reached over the first 2 s) with matches that see only y.
fn fly(seed: u64, config: EstimatorConfig, settle_s: f32, corridor_s: f32) -> Flight {
    let mut rng = Gauss(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut est = Estimator::new(config);
    let mut wind = [rng.normal(WIND_SIGMA_M_S), rng.normal(WIND_SIGMA_M_S)];
    let accel_bias = [rng.normal(0.03), rng.normal(0.03), rng.normal(0.03)];
    let fade = libm::expf(-DT / WIND_TAU_S);
    let kick = WIND_SIGMA_M_S * sqrtf(1.0 - fade * fade);
    let (mut x, mut v, mut tilt) = (0.0f32, 0.0f32, (0.0f32, 0.0f32));
    let mut reference = (0.0f32, 0.0f32);
    let flying = Situation {
        disarmed: false,
        rotors_carry: true,
        lidar_lost: false,
        ground_height_m: 0.05,
    };
    let mut flight = Flight {
        worst_velocity_std: 0.0,
        end_velocity_error: 0.0,
        end_velocity_std: 0.0,
        position_lost_s: None,
    };
    let steps = ((settle_s + corridor_s) / DT) as usize;
    for k in 1..=steps {
        let t = k as f32 * DT;
        let into = t - settle_s;
        let a = if (0.0..2.0).contains(&into) {
            0.25
        } else {
            0.0
        };
        v += a * DT;
        x += v * DT;
        for w in &mut wind {
            *w = fade * *w + kick * rng.normal(1.0);
        }
        // Drag on the air-relative velocity; thrust makes up the rest of the acceleration.
        let air = [v - wind[0], -wind[1]];
        let per_s = LINEAR_PER_S + QUADRATIC_PER_M * libm::hypotf(air[0], air[1]);
        let thrust = [a + per_s * air[0], per_s * air[1], GRAVITY_M_S2];
        let norm = sqrtf(thrust.iter().map(|t| t * t).sum());
        let now = (asinf(-thrust[1] / norm), atan2f(thrust[0], thrust[2]));
        let rate = ((now.0 - tilt.0) / DT, (now.1 - tilt.1) / DT);
        tilt = now;
        // The accelerometer reads the body-frame specific force, acceleration minus gravity.
        let r = crate::estimate::imu::rotation(&Tilt::from_angles(tilt.0, tilt.1), (0.0, 1.0));
        let specific = r.transpose() * nalgebra::Vector3::new(a, 0.0, GRAVITY_M_S2);
        let imu = ImuSample {
            t_s: t as f64,
            gyro_rad_s: [
                rate.0 + rng.normal(GYRO_SIGMA),
                rate.1 + rng.normal(GYRO_SIGMA),
                rng.normal(GYRO_SIGMA),
            ],
            accel_m_s2: core::array::from_fn(|i| {
                specific[i] + accel_bias[i] + rng.normal(ACCEL_SIGMA)
            }),
        };
        assert!(est.predict(&imu, DT));
        if k % 25 == 0 {
            let range = HEIGHT_M / (libm::cosf(tilt.0) * libm::cosf(tilt.1));
            est.fuse_sonar(&SonarSample {
                t_s: t as f64,
                range_m: range,
            });
        }
        if k % 100 == 0 {
            let m = ScanMatchDelta {
                t_s: t as f64,
                status: ScanMatchStatus::Matched,
                dx_m: x - reference.0 + rng.normal(0.01),
                dy_m: rng.normal(0.01),
                dtheta_rad: rng.normal(0.002),
                covariance: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 4e-6]],
                degenerate_axis: (into > 0.0).then_some([1.0, 0.0]),
                becomes_reference: true,
            };
            est.fuse_scan_match(&m, 0.0);
            reference = (x, 0.0);
        }
        est.fuse_situation(&flying);
        if into <= 0.0 {
            continue;
        }
        if let Horizontal::Across(along) = est.horizontal() {
            flight.worst_velocity_std = flight.worst_velocity_std.max(along.along_velocity_std_m_s);
            if flight.position_lost_s.is_none()
                && along.along_std_m > config.ekf.degraded_max_position_std_m
            {
                flight.position_lost_s = Some(into);
            }
        }
    }
    let p = est.ekf().covariance();
    flight.end_velocity_std = sqrtf(p[(ix::VEL, ix::VEL)]);
    flight.end_velocity_error = (est.ekf().state()[ix::VEL] - v) / flight.end_velocity_std;
    flight
}

/// Flies `seeds` corridors of `corridor_s` after a 10 s hover; prints each and returns the
/// worst along-axis velocity one-sigma and the mean squared normalised velocity error.
fn corridors(config: EstimatorConfig, seeds: u64, corridor_s: f32) -> (f32, f32) {
    let (mut worst, mut sum_squared) = (0.0f32, 0.0);
    for seed in 0..seeds {
        let f = fly(seed, config, 10.0, corridor_s);
        std::println!(
            "seed {seed}: along-axis velocity one-sigma at most {:.3} m/s, {:.3} at the end \
             (error {:.2} sigma); position past {} m after {:?} s",
            f.worst_velocity_std,
            f.end_velocity_std,
            f.end_velocity_error,
            config.ekf.degraded_max_position_std_m,
            f.position_lost_s,
        );
        worst = worst.max(f.worst_velocity_std);
        sum_squared += f.end_velocity_error * f.end_velocity_error;
    }
    (worst, sum_squared / seeds as f32)
}

#[test]
fn drag_along_the_unobserved_axis_slows_the_loss_of_the_speed_along_a_corridor() {
    let config = EstimatorConfig::default();
    let (worst, mean) = corridors(config, 10, 20.0);
    let mut widened = config;
    widened.drag.unobserved_specific_force_std_m_s2 = widened.drag.specific_force_std_m_s2;
    let (worst_widened, _) = corridors(widened, 10, 20.0);
    std::println!(
        "worst along-axis velocity one-sigma {worst:.3} m/s (widened everywhere \
         {worst_widened:.3}); mean squared normalised error {mean:.2}"
    );
    // The one-sigma reaches 0.59 m/s over these 20 s against 0.85 with the widened noise on
    // every axis, and it is still growing (0.74 after 40 s): above the degraded bound over a
    // long blank. The accelerometer bias walk the filter assumes (0.01 m/s^3/sqrt(Hz)) is what
    // the drag reading cannot tell from speed: at 0.003 the one-sigma stays at 0.46 over 40 s,
    // but the errors then run at 2-3.4 variances (the draughts, read as ground speed, are no
    // longer covered); fusing the drag at the white-noise equivalent of the draughts (0.2
    // m/s^2 a window: 0.03 m/s^2 correlated over 2 s) makes that honest again and puts the
    // one-sigma back at 0.61. Modelling the draught (a wind state) is what could bound it
    // honestly.
    assert!(
        worst < 0.75 * worst_widened,
        "{worst} against {worst_widened} widened"
    );
    // Honest: the errors' mean square over their variance is about one, draughts read as
    // ground speed and all.
    assert!(mean < 3.0, "velocity error {mean} variances");
}
