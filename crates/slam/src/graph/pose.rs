//! SE(2) poses in f64 for the pose graph.
//!
//! Core's `Pose2` is f32 because it runs on a flight controller; a graph composes thousands of
//! relative motions and solves normal equations whose conditioning f32 cannot carry, so the
//! companion side keeps its own f64 pose and converts at the boundary.

use plumbline_core::geom::{normalize_angle_f64, Pose2};

/// A 2-D pose (REP 103: x forward, y left, theta counter-clockwise, radians in (-pi, pi]),
/// also used for the relative motion between two poses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2d {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl Pose2d {
    pub const IDENTITY: Pose2d = Pose2d {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    /// A pose with its heading wrapped into (-pi, pi].
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Self {
            x,
            y,
            theta: normalize_angle_f64(theta),
        }
    }

    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }

    /// `self * other` in SE(2): `other` expressed in the frame of `self`, mapped to the parent.
    pub fn compose(self, other: Pose2d) -> Pose2d {
        let (s, c) = self.theta.sin_cos();
        Pose2d::new(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.theta + other.theta,
        )
    }

    pub fn inverse(self) -> Pose2d {
        let (s, c) = self.theta.sin_cos();
        Pose2d::new(
            -(c * self.x + s * self.y),
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// The pose of `other` in the frame of `self` (what an edge from `self` to `other` measures).
    pub fn between(self, other: Pose2d) -> Pose2d {
        self.inverse().compose(other)
    }
}

impl From<Pose2> for Pose2d {
    fn from(p: Pose2) -> Self {
        Pose2d::new(f64::from(p.x), f64::from(p.y), f64::from(p.theta))
    }
}

impl From<Pose2d> for Pose2 {
    /// Rounds to f32 for the onboard side.
    fn from(p: Pose2d) -> Self {
        Pose2::new(p.x as f32, p.y as f32, p.theta as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pose() -> impl Strategy<Value = Pose2d> {
        (-50.0..50.0f64, -50.0..50.0f64, -10.0..10.0f64).prop_map(|(x, y, t)| Pose2d::new(x, y, t))
    }

    fn close(a: Pose2d, b: Pose2d) -> bool {
        (a.x - b.x).abs() < 1e-9
            && (a.y - b.y).abs() < 1e-9
            && normalize_angle_f64(a.theta - b.theta).abs() < 1e-12
    }

    proptest! {
        #[test]
        fn between_recovers_the_composed_motion(a in pose(), d in pose()) {
            let b = a.compose(d);
            prop_assert!(close(a.between(b), d));
            prop_assert!(close(a.compose(a.inverse()), Pose2d::IDENTITY));
            prop_assert!(b.theta > -core::f64::consts::PI && b.theta <= core::f64::consts::PI);
        }
    }
}
