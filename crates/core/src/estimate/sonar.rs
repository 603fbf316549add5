//! Sonar measurement: height above a flat floor from a tilted range, `h = r cos(roll) cos(pitch)`.
//!
//! The sonar looks along body -z, so a tilted vehicle measures a slant range; the tilt comes from
//! the attitude filter. Ranges outside the sensor's band and tilts beyond its beam are refused
//! (counted as invalid) rather than fused.

use super::ekf::{ix, Ekf, Outcome, N};
use libm::cosf;
use nalgebra::{SMatrix, SVector};

/// Sonar model settings (defaults: MaxBotix MB1040, seed 002 sec. IV).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SonarConfig {
    /// Readings at or beyond these bounds carry no height: the MB1040 reports 6 in for anything
    /// closer and its maximum when no echo returns.
    pub min_range_m: f32,
    pub max_range_m: f32,
    /// Range one-sigma (m).
    pub range_std_m: f32,
    /// Tilt beyond which the beam no longer meets the floor below (rad).
    pub max_tilt_rad: f32,
    /// Height of the sensor above the floor when the vehicle sits on it (m); world z = 0 there.
    pub mount_height_m: f32,
}

impl Default for SonarConfig {
    fn default() -> Self {
        Self {
            min_range_m: 0.1524,
            max_range_m: 6.45,
            range_std_m: 0.03,
            max_tilt_rad: 0.5,
            mount_height_m: 0.0,
        }
    }
}

impl Ekf {
    /// Fuses one sonar range taken at the given tilt.
    pub fn fuse_sonar(&mut self, c: &SonarConfig, range_m: f32, roll: f32, pitch: f32) -> Outcome {
        let tilt_ok = roll.abs() <= c.max_tilt_rad && pitch.abs() <= c.max_tilt_rad;
        if !(range_m.is_finite() && range_m > c.min_range_m && range_m < c.max_range_m && tilt_ok) {
            return Outcome::Invalid;
        }
        let k = cosf(roll) * cosf(pitch);
        let height = range_m * k - c.mount_height_m;
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::POS + 2)] = 1.0;
        let var = (c.range_std_m * k) * (c.range_std_m * k);
        let residual = SVector::<f32, 1>::new(height - self.x[ix::POS + 2]);
        self.update(residual, h, SMatrix::<f32, 1, 1>::new(var))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::EkfConfig;

    #[test]
    fn tilted_range_gives_the_vertical_height() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS + 2] = 1.0;
        let c = SonarConfig::default();
        // At 1 m height with roll 0.2 and pitch 0.1 the slant range is 1 / (cos 0.2 cos 0.1).
        let r = 1.0 / (cosf(0.2) * cosf(0.1));
        let before = f.x;
        assert_eq!(f.fuse_sonar(&c, r, 0.2, 0.1), Outcome::Accepted);
        assert!((f.x - before).norm() < 1e-5);
        // And a true change of height pulls the estimate.
        for _ in 0..20 {
            f.fuse_sonar(&c, 1.05, 0.0, 0.0);
        }
        assert!((f.x[ix::POS + 2] - 1.05).abs() < 0.01);
    }

    #[test]
    fn out_of_band_ranges_and_steep_tilts_are_refused() {
        let mut f = Ekf::new(EkfConfig::default());
        let c = SonarConfig::default();
        assert_eq!(f.fuse_sonar(&c, 0.05, 0.0, 0.0), Outcome::Invalid);
        // The device's own floor and ceiling values mean "too close" and "no echo".
        assert_eq!(f.fuse_sonar(&c, 0.1524, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, 6.45, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, 9.0, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, f32::NAN, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, 1.0, 0.8, 0.0), Outcome::Invalid);
    }

    #[test]
    fn a_jump_to_a_table_top_is_gated() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS + 2] = 1.0;
        // Flying over a 0.7 m table: range 0.3 m is 0.7 m off, many sigma.
        assert_eq!(
            f.fuse_sonar(&SonarConfig::default(), 0.3, 0.0, 0.0),
            Outcome::Rejected
        );
    }
}
