//! At-rest measurement: a disarmed vehicle sits still on the floor it took off from.
//!
//! Velocity zero and height zero, fused while the motors are stopped. Before takeoff this pins
//! the vertical accelerometer bias and the velocity the IMU alone would let wander (the sonar is
//! blind below its 6 in minimum), so the vehicle leaves the ground with a settled filter.

use super::ekf::{ix, Ekf, Outcome, N};
use nalgebra::{SMatrix, SVector};

/// How still "at rest" is taken to be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtRestConfig {
    /// One-sigma of the zero-velocity measurement (m/s): vibration, a hand on the frame.
    pub velocity_std_m_s: f32,
    /// One-sigma of the zero-height measurement (m): landing gear compression, a soft floor.
    pub height_std_m: f32,
    /// Fused at most this often (s). What spoils "still" (vibration, a hand on the frame)
    /// changes slowly, so readings a step apart are not independent; fused at every IMU step
    /// it would claim five times the information at 500 Hz, and after a landing it would be a
    /// third of the closed loop's cost.
    pub period_s: f32,
}

impl Default for AtRestConfig {
    fn default() -> Self {
        Self {
            velocity_std_m_s: 0.05,
            height_std_m: 0.02,
            period_s: 0.01,
        }
    }
}

impl Ekf {
    /// Fuses "still, on the floor": velocity (3) and height (1) measured as zero.
    pub fn fuse_at_rest(&mut self, c: &AtRestConfig) -> Outcome {
        let mut h = SMatrix::<f32, 4, N>::zeros();
        for i in 0..3 {
            h[(i, ix::VEL + i)] = 1.0;
        }
        h[(3, ix::POS + 2)] = 1.0;
        let residual = SVector::<f32, 4>::new(
            -self.x[ix::VEL],
            -self.x[ix::VEL + 1],
            -self.x[ix::VEL + 2],
            -self.x[ix::POS + 2],
        );
        let (v, z) = (
            c.velocity_std_m_s * c.velocity_std_m_s,
            c.height_std_m * c.height_std_m,
        );
        let r = SMatrix::<f32, 4, 4>::from_diagonal(&SVector::<f32, 4>::new(v, v, v, z));
        self.update(residual, h, r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::EkfConfig;
    use crate::estimate::imu::tests::hover_step;
    use crate::estimate::imu::ImuStep;

    #[test]
    fn learns_the_vertical_accelerometer_bias_while_sitting_still() {
        let mut f = Ekf::new(EkfConfig::default());
        // The accelerometer reads 0.2 m/s^2 high on z.
        let mut step: ImuStep = hover_step();
        step.accel_m_s2[2] += 0.2;
        for k in 0..5000 {
            f.predict(&step, 0.002).unwrap();
            if k % 10 == 0 {
                assert_eq!(f.fuse_at_rest(&AtRestConfig::default()), Outcome::Accepted);
            }
        }
        assert!(
            (f.state()[ix::ACCEL_BIAS + 2] - 0.2).abs() < 0.02,
            "{}",
            f.state()[ix::ACCEL_BIAS + 2]
        );
        assert!(f.state()[ix::POS + 2].abs() < 0.01 && f.state()[ix::VEL + 2].abs() < 0.01);
    }
}
