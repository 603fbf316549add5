//! SE(2) algebra in f64 for the std side, where long trajectories with large offsets are composed
//! (f32 would lose millimetres at x = 600 m).

use crate::carmen::OdomPose;
use plumbline_core::geom::normalize_angle_f64;

impl OdomPose {
    pub fn new(x_m: f64, y_m: f64, theta_rad: f64) -> Self {
        Self {
            x_m,
            y_m,
            theta_rad: normalize_angle_f64(theta_rad),
        }
    }

    pub fn compose(self, o: OdomPose) -> OdomPose {
        let (s, c) = self.theta_rad.sin_cos();
        OdomPose::new(
            c * o.x_m - s * o.y_m + self.x_m,
            s * o.x_m + c * o.y_m + self.y_m,
            self.theta_rad + o.theta_rad,
        )
    }

    pub fn inverse(self) -> OdomPose {
        let (s, c) = self.theta_rad.sin_cos();
        OdomPose::new(
            -(c * self.x_m + s * self.y_m),
            s * self.x_m - c * self.y_m,
            -self.theta_rad,
        )
    }

    /// `inverse(self) * other`: the motion to `other` seen from `self`.
    pub fn between(self, other: OdomPose) -> OdomPose {
        self.inverse().compose(other)
    }

    pub fn to_f32(self) -> plumbline_core::geom::Pose2 {
        plumbline_core::geom::Pose2::new(self.x_m as f32, self.y_m as f32, self.theta_rad as f32)
    }

    pub fn from_f32(p: plumbline_core::geom::Pose2) -> Self {
        OdomPose::new(p.x as f64, p.y as f64, p.theta as f64)
    }
}
