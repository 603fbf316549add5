//! Roll and pitch from gyro and accelerometer: a complementary filter with gyro-bias estimation.
//!
//! The gyro is integrated for the fast part; the accelerometer's gravity direction pulls the tilt
//! back slowly (proportional gain) and trims the gyro bias (integral gain), in the manner of
//! Mahony's nonlinear complementary filter. A multirotor's accelerometer sees mostly thrust, not
//! gravity, while it accelerates, so the pull is weighted down as the specific force departs from
//! 1 g and the gain is kept low: the filter trusts the gyro over seconds, the accelerometer over
//! tens of seconds. Heading is not estimated here: the EKF owns yaw, observed by scan matching.

use super::ekf::all_finite;
use crate::fast_math::atan2_approx;
use crate::msgs::GRAVITY_M_S2;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Gains of the tilt filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeConfig {
    /// Proportional pull toward the accelerometer's gravity direction (rad/s per rad of error).
    pub kp_per_s: f32,
    /// Integral gain of the gyro-bias estimate (rad/s^2 per rad of error).
    pub ki_per_s2: f32,
    /// Specific-force magnitude error (fraction of 1 g) at which the accelerometer is ignored.
    pub accel_reject_fraction: f32,
    /// Bound on the gyro-bias estimate (rad/s), so a long misleading accelerometer cannot run it off.
    pub max_bias_rad_s: f32,
    /// The initial tilt is the direction of the accelerometer averaged over this long (s) from
    /// the first usable sample; the vehicle sits still on the floor meanwhile. One sample of an
    /// ADIS16365-class unit at 500 Hz is about 0.45 m/s^2 off, 2.6 degrees of tilt: taken
    /// alone it left the tilt that far off, the EKF's accelerometer bias soaked up most of it,
    /// and in IMU-only flight the vehicle then flew that tilt into a wall.
    pub align_s: f32,
}

impl AttitudeConfig {
    /// Gains for a filter that stands alone (no EKF correcting its tilt): the accelerometer
    /// pulls within seconds and the gyro bias is learned within tens of seconds.
    pub fn standalone() -> Self {
        Self {
            kp_per_s: 0.5,
            ki_per_s2: 0.05,
            ..Self::default()
        }
    }
}

impl Default for AttitudeConfig {
    /// Gains for use under the EKF, which corrects the tilt from the lidar: the accelerometer's
    /// pull is weak because a multirotor's accelerometer mostly sees thrust, not gravity.
    fn default() -> Self {
        Self {
            kp_per_s: 0.05,
            ki_per_s2: 0.002,
            accel_reject_fraction: 0.25,
            max_bias_rad_s: 0.1,
            align_s: 0.4,
        }
    }
}

/// Roll and pitch (ZYX Euler, FLU) with their sines and cosines. The filter works out this once
/// per change of its attitude; the prediction, the measurement models and the controllers read
/// it at every step, and taking Euler angles out of the quaternion each time cost more than the
/// filter's own update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tilt {
    pub roll_rad: f32,
    pub pitch_rad: f32,
    pub sin_roll: f32,
    pub cos_roll: f32,
    pub sin_pitch: f32,
    pub cos_pitch: f32,
}

impl Tilt {
    pub const LEVEL: Self = Self {
        roll_rad: 0.0,
        pitch_rad: 0.0,
        sin_roll: 0.0,
        cos_roll: 1.0,
        sin_pitch: 0.0,
        cos_pitch: 1.0,
    };

    pub fn from_angles(roll_rad: f32, pitch_rad: f32) -> Self {
        let (sin_roll, cos_roll) = libm::sincosf(roll_rad);
        let (sin_pitch, cos_pitch) = libm::sincosf(pitch_rad);
        Self {
            roll_rad,
            pitch_rad,
            sin_roll,
            cos_roll,
            sin_pitch,
            cos_pitch,
        }
    }

    /// The tilt of a body-to-world rotation, from the third row of its matrix
    /// (`-sin(pitch)`, `cos(pitch) sin(roll)`, `cos(pitch) cos(roll)`).
    fn of(q: &UnitQuaternion<f32>) -> Self {
        let (w, x, y, z) = (q.w, q.i, q.j, q.k);
        let sin_pitch = (-2.0 * (x * z - w * y)).clamp(-1.0, 1.0);
        let r21 = 2.0 * (y * z + w * x);
        let r22 = 1.0 - 2.0 * (x * x + y * y);
        let cos_pitch = libm::sqrtf(r21 * r21 + r22 * r22);
        // The angles to about 1e-5 rad, a thousandth of the tilt filter's own error, at a
        // third of the cost of libm's `atan2f` and `asinf`, which were half of a step's update.
        let roll_rad = atan2_approx(r21, r22);
        let (sin_roll, cos_roll) = if cos_pitch > 1e-6 {
            (r21 / cos_pitch, r22 / cos_pitch)
        } else {
            libm::sincosf(roll_rad)
        };
        Self {
            roll_rad,
            pitch_rad: atan2_approx(sin_pitch, cos_pitch),
            sin_roll,
            cos_roll,
            sin_pitch,
            cos_pitch: cos_pitch.min(1.0),
        }
    }
}

/// Why a sample was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttitudeError {
    NonFinite,
    BadDt,
}

/// Tilt filter state: body-to-world rotation and gyro bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeFilter {
    pub config: AttitudeConfig,
    rotation: UnitQuaternion<f32>,
    /// The tilt of `rotation`, kept up to date with it.
    tilt: Tilt,
    bias_rad_s: Vector3<f32>,
    /// Sum of the accelerometer samples of the initial alignment, and the time they span (s).
    align_sum: Vector3<f32>,
    aligned_s: f32,
}

impl AttitudeFilter {
    pub fn new(config: AttitudeConfig) -> Self {
        Self {
            config,
            rotation: UnitQuaternion::identity(),
            tilt: Tilt::LEVEL,
            bias_rad_s: Vector3::zeros(),
            align_sum: Vector3::zeros(),
            aligned_s: 0.0,
        }
    }

    /// Roll and pitch (ZYX Euler, FLU), radians.
    pub fn roll_pitch(&self) -> (f32, f32) {
        (self.tilt.roll_rad, self.tilt.pitch_rad)
    }

    /// Roll and pitch with their sines and cosines.
    pub fn tilt(&self) -> &Tilt {
        &self.tilt
    }

    fn set_rotation(&mut self, rotation: UnitQuaternion<f32>) {
        self.rotation = rotation;
        self.tilt = Tilt::of(&rotation);
    }

    /// The gyro reading with the estimated bias removed (rad/s).
    pub fn corrected_rate(&self, gyro_rad_s: [f32; 3]) -> [f32; 3] {
        let w = Vector3::from(gyro_rad_s) - self.bias_rad_s;
        [w.x, w.y, w.z]
    }

    /// Applies a small tilt correction estimated elsewhere (the EKF): `error` is the angle
    /// (rad) about the x and y axes of a world frame whose heading is `heading_rad`, such that
    /// the true attitude is `exp(error) * estimate`.
    pub fn correct_tilt(&mut self, error: [f32; 2], heading_rad: f32) {
        if !(error.iter().all(|e| e.is_finite()) && heading_rad.is_finite()) {
            return;
        }
        // Into the heading frame, then into this filter's own (free-heading) world frame.
        let (_, _, own_heading) = self.rotation.euler_angles();
        let (s, c) = libm::sincosf(own_heading - heading_rad);
        let axis = Vector3::new(
            c * error[0] - s * error[1],
            s * error[0] + c * error[1],
            0.0,
        );
        self.set_rotation(UnitQuaternion::from_scaled_axis(axis) * self.rotation);
    }

    /// Adds a gyro x/y bias correction (rad/s, body) estimated elsewhere (the EKF).
    pub fn correct_bias(&mut self, error: [f32; 2]) {
        if !error.iter().all(|e| e.is_finite()) {
            return;
        }
        let b = self.config.max_bias_rad_s;
        for (i, e) in error.iter().enumerate() {
            self.bias_rad_s[i] = (self.bias_rad_s[i] + e).clamp(-b, b);
        }
    }

    /// One step with a gyro and accelerometer sample. Bad samples leave the state unchanged.
    pub fn update(
        &mut self,
        gyro_rad_s: [f32; 3],
        accel_m_s2: [f32; 3],
        dt: f32,
    ) -> Result<(), AttitudeError> {
        // A NaN fails both comparisons.
        if !(dt > 0.0 && dt < f32::INFINITY) {
            return Err(AttitudeError::BadDt);
        }
        if !(all_finite(&gyro_rad_s) && all_finite(&accel_m_s2)) {
            return Err(AttitudeError::NonFinite);
        }
        let gyro = Vector3::from(gyro_rad_s);
        let accel = Vector3::from(accel_m_s2);
        let c = &self.config;
        let mut omega = gyro - self.bias_rad_s;
        let norm = accel.norm();
        let misfit = libm::fabsf(norm / GRAVITY_M_S2 - 1.0) / c.accel_reject_fraction;
        let weight = (1.0 - misfit).max(0.0);
        if weight > 0.0 && self.aligned_s < c.align_s {
            // Alignment at rest: the tilt is that of the mean specific force so far, taken at
            // once instead of converged to.
            self.align_sum += accel;
            self.aligned_s += dt;
            let tilt = UnitQuaternion::rotation_between(&self.align_sum, &Vector3::z());
            self.set_rotation(tilt.unwrap_or_else(UnitQuaternion::identity));
            return Ok(());
        }
        if weight > 0.0 {
            // Error between measured and predicted "up" in the body frame (Mahony's e).
            let up_measured = accel * (1.0 / norm);
            // The predicted "up" is the rotation's third row, which the tilt already holds.
            let t = &self.tilt;
            let up_predicted = Vector3::new(
                -t.sin_pitch,
                t.cos_pitch * t.sin_roll,
                t.cos_pitch * t.cos_roll,
            );
            let error = up_measured.cross(&up_predicted) * weight;
            let bias = self.bias_rad_s - error * (c.ki_per_s2 * dt);
            self.bias_rad_s = bias.map(|b| b.clamp(-c.max_bias_rad_s, c.max_bias_rad_s));
            omega += error * c.kp_per_s;
        }
        // The step's rotation as (1, omega dt / 2), normalised: it turns by 2 atan(theta / 2),
        // short of theta by theta^3 / 12, a few f32 roundings at the milliradians of a step,
        // and it needs no sine or cosine.
        let half = omega * (0.5 * dt);
        let turn = Quaternion::new(1.0, half.x, half.y, half.z);
        self.set_rotation(UnitQuaternion::new_normalize(
            self.rotation.into_inner() * turn,
        ));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use libm::{cosf, sinf};

    /// Specific force of a vehicle at rest with the given roll and pitch (FLU, ZYX Euler).
    fn resting_accel(roll: f32, pitch: f32) -> [f32; 3] {
        let g = GRAVITY_M_S2;
        [
            -g * sinf(pitch),
            g * cosf(pitch) * sinf(roll),
            g * cosf(pitch) * cosf(roll),
        ]
    }

    #[test]
    fn converges_to_the_resting_tilt_from_level() {
        let mut f = AttitudeFilter::new(AttitudeConfig::standalone());
        f.update([0.0; 3], resting_accel(0.0, 0.0), 0.002).unwrap();
        for _ in 0..20_000 {
            f.update([0.0; 3], resting_accel(0.2, -0.1), 0.002).unwrap();
        }
        let (roll, pitch) = f.roll_pitch();
        assert!(
            (roll - 0.2).abs() < 2e-3 && (pitch + 0.1).abs() < 2e-3,
            "{roll} {pitch}"
        );
    }

    #[test]
    fn follows_a_gyro_rotation_and_learns_a_constant_bias() {
        let mut f = AttitudeFilter::new(AttitudeConfig::standalone());
        let bias = [0.02, -0.015, 0.0];
        // At rest, level, with a biased gyro: the bias is learned and the tilt stays near zero.
        for _ in 0..100_000 {
            f.update(bias, resting_accel(0.0, 0.0), 0.002).unwrap();
        }
        let w = f.corrected_rate(bias);
        assert!(w[0].abs() < 1e-3 && w[1].abs() < 1e-3, "{w:?}");
        // Now roll at 0.5 rad/s for 0.4 s with a matching accelerometer: roll reaches 0.2.
        for k in 1..=200 {
            let roll = 0.5 * 0.002 * k as f32;
            f.update(
                [0.5 + bias[0], bias[1], 0.0],
                resting_accel(roll, 0.0),
                0.002,
            )
            .unwrap();
        }
        let (roll, pitch) = f.roll_pitch();
        assert!(
            (roll - 0.2).abs() < 3e-3 && pitch.abs() < 3e-3,
            "{roll} {pitch}"
        );
    }

    #[test]
    fn first_sample_sets_the_tilt() {
        let mut f = AttitudeFilter::new(AttitudeConfig::default());
        f.update([0.0; 3], resting_accel(0.1, 0.25), 0.002).unwrap();
        let (roll, pitch) = f.roll_pitch();
        assert!(
            (roll - 0.1).abs() < 1e-4 && (pitch - 0.25).abs() < 1e-4,
            "{roll} {pitch}"
        );
    }

    #[test]
    fn alignment_averages_out_the_accelerometer_noise() {
        let mut f = AttitudeFilter::new(AttitudeConfig::default());
        let truth = resting_accel(0.05, -0.02);
        // Noise of one 500 Hz sample (0.45 m/s^2, 2.6 degrees of tilt), alternating in sign.
        let noisy = |k: usize| {
            let n = if k.is_multiple_of(2) { 0.45 } else { -0.45 };
            [truth[0] + n, truth[1] - n, truth[2]]
        };
        f.update([0.0; 3], noisy(0), 0.002).unwrap();
        let (roll, pitch) = f.roll_pitch();
        assert!((pitch + 0.02).abs() > 0.04, "one sample is that far off");
        for k in 1..200 {
            f.update([0.0; 3], noisy(k), 0.002).unwrap();
        }
        let (roll_end, pitch_end) = f.roll_pitch();
        assert!(
            (roll_end - 0.05).abs() < 5e-4 && (pitch_end + 0.02).abs() < 5e-4,
            "{roll} {pitch} -> {roll_end} {pitch_end}"
        );
    }

    #[test]
    fn accelerating_flight_does_not_drag_the_tilt() {
        let mut f = AttitudeFilter::new(AttitudeConfig::default());
        f.update([0.0; 3], resting_accel(0.0, 0.0), 0.002).unwrap();
        // 1.5 g of specific force (a hard climb): beyond the rejection band, gyro only.
        for _ in 0..1000 {
            f.update([0.0; 3], [3.0, 0.0, 1.5 * GRAVITY_M_S2], 0.002)
                .unwrap();
        }
        let (roll, pitch) = f.roll_pitch();
        assert_eq!((roll, pitch), (0.0, 0.0));
    }

    #[test]
    fn tilt_correction_rotates_about_the_given_world_axis() {
        let mut f = AttitudeFilter::new(AttitudeConfig::default());
        f.update([0.0; 3], resting_accel(0.0, 0.0), 0.002).unwrap();
        // Heading of the corrector is 90 degrees: its x axis is this filter's -y axis, so an
        // error about its x is a rotation about -y here, i.e. negative pitch.
        f.correct_tilt([0.05, 0.0], core::f32::consts::FRAC_PI_2);
        let (roll, pitch) = f.roll_pitch();
        assert!(
            roll.abs() < 1e-5 && (pitch + 0.05).abs() < 1e-4,
            "{roll} {pitch}"
        );
    }

    #[test]
    fn tilt_agrees_with_the_euler_angles_of_the_rotation() {
        for (roll, pitch, yaw) in [
            (0.0, 0.0, 0.0),
            (0.3, -0.2, 1.0),
            (-0.5, 0.4, -2.5),
            (0.1, 1.5, 3.0),
        ] {
            let t = Tilt::of(&UnitQuaternion::from_euler_angles(roll, pitch, yaw));
            let expected = Tilt::from_angles(roll, pitch);
            for (got, want) in [
                (t.roll_rad, roll),
                (t.pitch_rad, pitch),
                (t.sin_roll, expected.sin_roll),
                (t.cos_roll, expected.cos_roll),
                (t.sin_pitch, expected.sin_pitch),
                (t.cos_pitch, expected.cos_pitch),
            ] {
                assert!((got - want).abs() < 2e-3, "{t:?} vs {expected:?}");
            }
        }
    }

    #[test]
    fn bad_samples_are_refused() {
        let mut f = AttitudeFilter::new(AttitudeConfig::default());
        let before = f;
        assert_eq!(
            f.update([f32::NAN, 0.0, 0.0], [0.0, 0.0, 9.8], 0.002),
            Err(AttitudeError::NonFinite)
        );
        assert_eq!(
            f.update([0.0; 3], [0.0, 0.0, 9.8], -1.0),
            Err(AttitudeError::BadDt)
        );
        assert_eq!(f, before);
    }
}
