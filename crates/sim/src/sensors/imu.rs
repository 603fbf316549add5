//! A MEMS IMU: gyroscope and accelerometer with white noise (noise density), a bias that walks
//! (bias random walk) and an initial bias, sampled at a fixed rate.

use crate::math::Vec3;
use crate::rng::Rng;
use plumbline_core::msgs::ImuSample;

#[derive(Clone, Debug, PartialEq)]
pub struct ImuParams {
    pub rate_hz: f64,
    /// rad/s/√Hz
    pub gyro_noise_density: f64,
    /// rad/s/√s
    pub gyro_bias_walk: f64,
    /// rad/s, one sigma
    pub gyro_initial_bias: f64,
    /// m/s²/√Hz
    pub accel_noise_density: f64,
    /// m/s²/√s
    pub accel_bias_walk: f64,
    /// m/s², one sigma
    pub accel_initial_bias: f64,
}

impl ImuParams {
    /// An ADIS16365-class unit (seed 002's IMU): gyro noise density 0.044 °/s/√Hz, accelerometer
    /// about 2 mg/√Hz, sampled at 500 Hz; bias walks and initial biases of that class.
    pub fn adis16365() -> Self {
        Self {
            rate_hz: 500.0,
            gyro_noise_density: 0.044f64.to_radians(),
            gyro_bias_walk: 2e-5,
            gyro_initial_bias: 0.003,
            accel_noise_density: 0.02,
            accel_bias_walk: 3e-4,
            accel_initial_bias: 0.03,
        }
    }
}

/// Samples between bias random-walk updates.
const BIAS_EVERY: u64 = 10;

/// An IMU in flight.
#[derive(Clone, Debug)]
pub struct Imu {
    /// Per-sample standard deviations, worked out once: sample period, white noise of the gyro
    /// and accelerometer, and one bias-walk step of each.
    dt_s: f64,
    sigma: Sigmas,
    rng: Rng,
    gyro_bias: Vec3,
    accel_bias: Vec3,
    next_s: f64,
    count: u64,
}

#[derive(Clone, Copy, Debug)]
struct Sigmas {
    gyro: f64,
    accel: f64,
    gyro_walk: f64,
    accel_walk: f64,
}

#[inline]
fn gauss3(rng: &mut Rng, sigma: f64) -> Vec3 {
    Vec3::new(rng.gauss(), rng.gauss(), rng.gauss()) * sigma
}

impl Imu {
    pub fn new(params: ImuParams, mut rng: Rng) -> Self {
        let gyro_bias = gauss3(&mut rng, params.gyro_initial_bias);
        let accel_bias = gauss3(&mut rng, params.accel_initial_bias);
        let dt_s = 1.0 / params.rate_hz;
        let root_rate = params.rate_hz.sqrt();
        // The biases walk in steps of BIAS_EVERY samples: the same variance growth (σ² t) for a
        // sixth of the random draws.
        let walk_step = (BIAS_EVERY as f64 * dt_s).sqrt();
        let sigma = Sigmas {
            gyro: params.gyro_noise_density * root_rate,
            accel: params.accel_noise_density * root_rate,
            gyro_walk: params.gyro_bias_walk * walk_step,
            accel_walk: params.accel_bias_walk * walk_step,
        };
        Self {
            dt_s,
            sigma,
            rng,
            gyro_bias,
            accel_bias,
            next_s: 0.0,
            count: 0,
        }
    }

    /// A sample if one is due at `t_s`. `rate` is the true body rate and `specific_force` the
    /// true body-frame specific force (acceleration minus gravity), both from the dynamics.
    #[inline]
    pub fn sample(&mut self, t_s: f64, rate: Vec3, specific_force: Vec3) -> Option<ImuSample> {
        if t_s < self.next_s {
            return None;
        }
        let sigma = self.sigma;
        self.next_s += self.dt_s;
        self.count += 1;
        if self.count.is_multiple_of(BIAS_EVERY) {
            self.gyro_bias += gauss3(&mut self.rng, sigma.gyro_walk);
            self.accel_bias += gauss3(&mut self.rng, sigma.accel_walk);
        }
        let g = rate + self.gyro_bias + gauss3(&mut self.rng, sigma.gyro);
        let a = specific_force + self.accel_bias + gauss3(&mut self.rng, sigma.accel);
        Some(ImuSample {
            t_s,
            gyro_rad_s: [g.x as f32, g.y as f32, g.z as f32],
            accel_m_s2: [a.x as f32, a.y as f32, a.z as f32],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resting_imu_reads_gravity_with_the_datasheet_noise() {
        let params = ImuParams {
            gyro_bias_walk: 0.0,
            accel_bias_walk: 0.0,
            ..ImuParams::adis16365()
        };
        let mut imu = Imu::new(params.clone(), Rng::new(11));
        let (b_g, b_a) = (imu.gyro_bias, imu.accel_bias);
        let n = 50_000;
        let (mut sg, mut sg2, mut sa) = (0.0, 0.0, 0.0);
        let mut count = 0;
        for i in 0..n * 2 {
            // Physics at 1 kHz, IMU at 500 Hz: every other step yields a sample.
            let t = i as f64 * 1e-3;
            if let Some(s) = imu.sample(t, Vec3::ZERO, Vec3::new(0.0, 0.0, 9.80665)) {
                let gx = s.gyro_rad_s[0] as f64 - b_g.x;
                sg += gx;
                sg2 += gx * gx;
                sa += s.accel_m_s2[2] as f64 - b_a.z;
                count += 1;
            }
        }
        assert_eq!(count, n);
        let sigma = params.gyro_noise_density * params.rate_hz.sqrt();
        let std = (sg2 / n as f64 - (sg / n as f64).powi(2)).sqrt();
        assert!(
            (std / sigma - 1.0).abs() < 0.02,
            "gyro std {std} vs {sigma}"
        );
        assert!((sa / n as f64 - 9.80665).abs() < 0.005, "accel mean");
    }

    #[test]
    fn bias_walk_grows_like_the_square_root_of_time() {
        // Variance of a random walk after T seconds is walk² T, checked over many seeds.
        let params = ImuParams {
            gyro_initial_bias: 0.0,
            ..ImuParams::adis16365()
        };
        let t_end = 20.0;
        let trials = 200;
        let mut var = 0.0;
        for seed in 0..trials {
            let mut imu = Imu::new(params.clone(), Rng::new(seed));
            let mut t = 0.0;
            while t < t_end {
                imu.sample(t, Vec3::ZERO, Vec3::ZERO);
                t += 1.0 / params.rate_hz;
            }
            var += imu.gyro_bias.x * imu.gyro_bias.x;
        }
        let expect = params.gyro_bias_walk * params.gyro_bias_walk * t_end;
        let ratio = var / trials as f64 / expect;
        assert!((0.75..1.25).contains(&ratio), "ratio {ratio}");
    }
}
