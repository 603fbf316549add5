//! What the horizontal estimate still knows, along the principal axes of its position
//! covariance.
//!
//! A scan match or a map pose in a featureless corridor observes the position across the
//! corridor and nothing along it: the variance along the axis grows with the velocity's while
//! the one across stays at centimetres. One bound on the larger variance throws both away.
//! Here the covariance is split along its principal axes (the direction of the smallest
//! variance is "across", the one perpendicular to it "along"), and each is judged on its own:
//!
//! - [`Horizontal::Known`]: both one-sigmas within `max_position_std_m`; fly anything.
//! - [`Horizontal::Across`]: only the across one is; the along-axis position and velocity
//!   one-sigmas are reported, and the estimate is *flyable* on a velocity setpoint (a mission
//!   leg down the corridor: the guidance keeps clear of the walls on the live scan and needs
//!   the velocity, not where along the corridor the vehicle is) while the along-axis velocity
//!   one-sigma is within `degraded_max_velocity_std_m_s` and the along-axis position one-sigma
//!   within `degraded_max_position_std_m`. Nothing but the velocity estimate keeps the vehicle
//!   from flying down the corridor faster than it thinks, and with the axis unobserved that
//!   estimate is the IMU's integral checked only by the drag reading, which holds its
//!   one-sigma near the velocity bound (about 0.47 m/s in the simulated building) while the
//!   position's grows past its own: the position bound is what ends a degraded leg there, and
//!   it also limits how long a leg flies on a speed the lidar cannot check (the bounds'
//!   documentation in [`super::ekf::EkfConfig`]).
//! - [`Horizontal::Unknown`]: neither, or a non-finite filter.

use super::ekf::{ix, Ekf};
use crate::matching::linalg::sym2_eigen;
use libm::sqrtf;

/// The along-axis state when only the across axis is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AcrossOnly {
    /// Unit vector (world x, y) of the best known horizontal direction.
    pub across_axis: [f32; 2],
    /// One-sigma of position across and along (m), and of velocity along (m/s).
    pub across_std_m: f32,
    pub along_std_m: f32,
    pub along_velocity_std_m_s: f32,
    /// Within the degraded bounds: a velocity-setpoint leg may fly on.
    pub flyable: bool,
}

/// What the estimate knows of the horizontal position (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Horizontal {
    Known,
    Across(AcrossOnly),
    Unknown,
}

impl Horizontal {
    /// The unit vector of the direction still known when only one is (None otherwise).
    pub fn across_axis(&self) -> Option<[f32; 2]> {
        match self {
            Horizontal::Across(a) => Some(a.across_axis),
            Horizontal::Known | Horizontal::Unknown => None,
        }
    }

    /// Known, or known across only and within the degraded bounds.
    pub fn flyable_on_velocity(&self) -> bool {
        match self {
            Horizontal::Known => true,
            Horizontal::Across(a) => a.flyable,
            Horizontal::Unknown => false,
        }
    }
}

impl Ekf {
    /// The horizontal estimate judged along its covariance's principal axes (module docs).
    pub fn horizontal(&self) -> Horizontal {
        if !self.is_finite() {
            return Horizontal::Unknown;
        }
        let p = &self.p;
        let (x, y) = (ix::POS, ix::POS + 1);
        let (largest, smallest, across) = sym2_eigen(p[(x, x)], p[(x, y)], p[(y, y)]);
        let c = &self.config;
        let bound = c.max_position_std_m * c.max_position_std_m;
        if largest <= bound {
            return Horizontal::Known;
        }
        if smallest > bound {
            return Horizontal::Unknown;
        }
        let along = [-across.y, across.x];
        let (vx, vy) = (ix::VEL, ix::VEL + 1);
        let velocity_variance = along[0] * along[0] * p[(vx, vx)]
            + 2.0 * along[0] * along[1] * p[(vx, vy)]
            + along[1] * along[1] * p[(vy, vy)];
        let along_std_m = sqrtf(largest);
        let along_velocity_std_m_s = sqrtf(velocity_variance.max(0.0));
        Horizontal::Across(AcrossOnly {
            across_axis: [across.x, across.y],
            across_std_m: sqrtf(smallest.max(0.0)),
            along_std_m,
            along_velocity_std_m_s,
            flyable: along_velocity_std_m_s <= c.degraded_max_velocity_std_m_s
                && along_std_m <= c.degraded_max_position_std_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::{EkfConfig, Outcome, N};

    /// A filter whose position covariance is `along` (variance, m^2) along the unit direction
    /// at `angle_rad` and `across` across it, with velocity variance `velocity` along it.
    fn corridor(angle_rad: f32, along: f32, across: f32, velocity: f32) -> Ekf {
        let mut f = Ekf::new(EkfConfig::default());
        let (c, s) = (libm::cosf(angle_rad), libm::sinf(angle_rad));
        let set = |f: &mut Ekf, i: usize, a: f32, b: f32| {
            f.p[(i, i)] = a * c * c + b * s * s;
            f.p[(i + 1, i + 1)] = a * s * s + b * c * c;
            f.p[(i, i + 1)] = (a - b) * c * s;
            f.p[(i + 1, i)] = (a - b) * c * s;
        };
        set(&mut f, ix::POS, along, across);
        set(&mut f, ix::VEL, velocity, 0.01);
        f
    }

    #[test]
    fn a_small_covariance_is_known_on_both_axes() {
        let f = Ekf::new(EkfConfig::default());
        assert_eq!(f.horizontal(), Horizontal::Known);
        assert!(f.is_valid());
    }

    #[test]
    fn a_corridor_along_a_diagonal_is_known_across_only() {
        // 2 m one-sigma along 30 degrees, 3 cm across, velocity 0.3 m/s along.
        let angle = core::f32::consts::FRAC_PI_6;
        let f = corridor(angle, 4.0, 9e-4, 0.09);
        assert!(!f.is_valid());
        let Horizontal::Across(a) = f.horizontal() else {
            panic!("{:?}", f.horizontal());
        };
        // The across axis is perpendicular to the corridor (either sign).
        let dot = a.across_axis[0] * libm::cosf(angle) + a.across_axis[1] * libm::sinf(angle);
        assert!(dot.abs() < 1e-3, "{a:?}");
        assert!((a.along_std_m - 2.0).abs() < 1e-3, "{a:?}");
        assert!((a.across_std_m - 0.03).abs() < 1e-3, "{a:?}");
        assert!((a.along_velocity_std_m_s - 0.3).abs() < 1e-3, "{a:?}");
        assert!(a.flyable);
        assert!(f.horizontal().flyable_on_velocity());
    }

    #[test]
    fn the_degraded_bounds_end_a_flyable_corridor() {
        let c = EkfConfig::default();
        let v = c.degraded_max_velocity_std_m_s;
        let fast = corridor(0.0, 4.0, 1e-3, 1.1 * v * 1.1 * v);
        assert!(!fast.horizontal().flyable_on_velocity());
        assert!(fast.horizontal().across_axis().is_some());
        let p = c.degraded_max_position_std_m;
        let far = corridor(0.0, 1.1 * p * 1.1 * p, 1e-3, 0.01);
        assert!(!far.horizontal().flyable_on_velocity());
        assert!(far.horizontal().across_axis().is_some());
    }

    #[test]
    fn a_filter_that_sees_only_y_loses_x_and_keeps_y() {
        use crate::estimate::attitude::Tilt;
        use crate::estimate::imu::ImuStep;
        use nalgebra::{SMatrix, SVector};
        // Hovering level on the IMU, with position y measured at 5 Hz (a corridor along x).
        let mut f = Ekf::new(EkfConfig::default());
        let hover = ImuStep {
            accel_m_s2: [0.0, 0.0, 9.81],
            gyro_rad_s: [0.0; 3],
            tilt: Tilt::LEVEL,
        };
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::POS + 1)] = 1.0;
        let r = SMatrix::<f32, 1, 1>::new(0.03 * 0.03);
        let mut lost_at_s = None;
        for step in 0..6000 {
            f.predict(&hover, 0.005).unwrap();
            if step % 40 == 0 {
                assert_eq!(f.update(SVector::zeros(), h, r), Outcome::Accepted);
            }
            if lost_at_s.is_none() && !f.is_valid() {
                lost_at_s = Some(step as f32 * 0.005);
            }
        }
        // Known answer: y held at centimetres, x lost within the 30 s.
        let lost_at_s = lost_at_s.expect("x is never observed");
        let Horizontal::Across(a) = f.horizontal() else {
            panic!("{:?}", f.horizontal());
        };
        assert!(a.across_axis[1].abs() > 0.999, "{a:?}");
        assert!(a.across_std_m < 0.05, "{a:?}");
        assert!(
            a.along_std_m > EkfConfig::default().max_position_std_m,
            "{a:?}"
        );
        // On the IMU alone the velocity along x is as lost as the position: not flyable.
        assert!(!a.flyable, "{a:?}, invalid after {lost_at_s} s");
    }

    #[test]
    fn both_axes_wide_or_a_non_finite_filter_is_unknown() {
        let wide = corridor(0.3, 4.0, 3.0, 0.01);
        assert_eq!(wide.horizontal(), Horizontal::Unknown);
        let mut nan = Ekf::new(EkfConfig::default());
        nan.x[ix::YAW] = f32::NAN;
        assert_eq!(nan.horizontal(), Horizontal::Unknown);
        assert!(!nan.horizontal().flyable_on_velocity());
    }
}
