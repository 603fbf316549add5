//! Sonar measurement: height above a flat floor from a tilted range, `h = r cos(roll) cos(pitch)`.
//!
//! The sonar looks along body -z, so a tilted vehicle measures a slant range; the tilt comes from
//! the attitude filter. Ranges outside the sensor's band and tilts beyond its beam are refused
//! (counted as invalid) rather than fused, except the device's "too close" value: it says the
//! floor is nearer than the minimum range, a bound on the height that is the only vertical
//! measurement a vehicle on its rotors has before it leaves the floor.

use super::ekf::{ix, Ekf, Outcome, N};
use libm::cosf;
use nalgebra::{SMatrix, SVector};

/// Sonar model settings (defaults: MaxBotix MB1040, seed 002 sec. IV).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SonarConfig {
    /// Readings beyond these bounds carry no height: the MB1040 reports its maximum when no echo
    /// returns, and 6 in (the minimum) for anything closer, which bounds the height from above.
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
        // The minimum to a tenth of a millimetre: a driver's unit conversion may not hit the
        // configured value to the last bit.
        let too_close = (range_m - c.min_range_m).abs() <= 1e-4;
        let in_band = range_m > c.min_range_m && range_m < c.max_range_m;
        if !(range_m.is_finite() && (in_band || too_close) && tilt_ok) {
            return Outcome::Invalid;
        }
        let k = cosf(roll) * cosf(pitch);
        // "Too close" is an inequality: an estimate at or below the bound agrees with it, one
        // above it is pulled to the bound (a constrained filter's projection). Without it a
        // vehicle still on the floor after arming has no vertical measurement at all, and the
        // IMU-only height can drift up to the take-off height while the vehicle sits there.
        // The bound lies three sigmas of range above the minimum: a floor that far can still
        // read as the minimum (rounding to whole inches, noise, a reading up to 50 ms old in a
        // climb), and pulling an estimate that is right would bend every take-off's climb.
        let range_m = if too_close {
            c.min_range_m + 3.0 * c.range_std_m
        } else {
            range_m
        };
        let height = range_m * k - c.mount_height_m;
        // An estimate the bound does not move is told nothing: the reading is refused as it
        // always was, so it neither ends nor extends a run of rejections (the touchdown reset).
        if too_close && self.x[ix::POS + 2] <= height {
            return Outcome::Invalid;
        }
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
        // The device's ceiling value means "no echo".
        assert_eq!(f.fuse_sonar(&c, 6.45, 0.0, 0.0), Outcome::Invalid);
        // "Too close" seen through a steep tilt says nothing about the floor below.
        assert_eq!(f.fuse_sonar(&c, 0.1524, 0.8, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, 9.0, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, f32::NAN, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.fuse_sonar(&c, 1.0, 0.8, 0.0), Outcome::Invalid);
    }

    #[test]
    fn too_close_bounds_the_height_from_above() {
        let c = SonarConfig::default();
        // An IMU-only height that drifted to 0.9 m (and knows it is unsure) while the sonar says
        // the floor is within its 6 in minimum: pulled under the bound.
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS + 2] = 0.9;
        f.reset_variance(&[(ix::POS + 2, 1.0)]);
        for _ in 0..5 {
            assert_eq!(f.fuse_sonar(&c, 0.1524, 0.0, 0.0), Outcome::Accepted);
        }
        // The bound: the minimum and three sigmas of range, 0.24 m.
        let z = f.x[ix::POS + 2];
        assert!(z < 0.2424 + 0.03 && z > 0.2, "height {z}");
        // A height under the bound agrees with it and is left where it is, even a little above
        // the minimum (a climb the 20 Hz sonar has not seen yet).
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS + 2] = 0.2;
        let before = f.x;
        assert_eq!(f.fuse_sonar(&c, 0.1524, 0.0, 0.0), Outcome::Invalid);
        assert_eq!(f.x, before);
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
