//! SE(2) poses and angle helpers (REP 103: x forward, y left, theta counter-clockwise).

use libm::{cosf, sinf, sqrtf};

/// Wraps an angle into (-pi, pi], the project's one angle convention.
pub fn normalize_angle(a: f32) -> f32 {
    use core::f32::consts::PI;
    // Already wrapped (the usual case: headings and their small differences, every step of
    // the flight loop): returned as it is, which is what the remainder gives, without one.
    if a > -PI && a <= PI {
        return a;
    }
    if !a.is_finite() {
        return a;
    }
    let mut r = libm::remainderf(a, 2.0 * PI);
    if r <= -PI {
        r += 2.0 * PI;
    }
    r
}

/// f64 twin of [`normalize_angle`] for the std side, where long trajectories are composed.
pub fn normalize_angle_f64(a: f64) -> f64 {
    use core::f64::consts::PI;
    if !a.is_finite() {
        return a;
    }
    let mut r = libm::remainder(a, 2.0 * PI);
    if r <= -PI {
        r += 2.0 * PI;
    }
    r
}

/// A 2-D point or vector in metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec2 {
    pub x: f32,
    pub y: f32,
}

impl Vec2 {
    pub const ZERO: Vec2 = Vec2 { x: 0.0, y: 0.0 };

    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    pub fn dot(self, o: Vec2) -> f32 {
        self.x * o.x + self.y * o.y
    }

    /// z component of the 3-D cross product; positive when `o` is counter-clockwise of `self`.
    pub fn cross(self, o: Vec2) -> f32 {
        self.x * o.y - self.y * o.x
    }

    pub fn norm_squared(self) -> f32 {
        self.dot(self)
    }

    pub fn norm(self) -> f32 {
        sqrtf(self.norm_squared())
    }

    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// Rotated a quarter turn counter-clockwise.
    pub fn perp(self) -> Vec2 {
        Vec2::new(-self.y, self.x)
    }
}

impl core::ops::Add for Vec2 {
    type Output = Vec2;
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}

impl core::ops::Sub for Vec2 {
    type Output = Vec2;
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}

impl core::ops::Mul<f32> for Vec2 {
    type Output = Vec2;
    fn mul(self, s: f32) -> Vec2 {
        Vec2::new(self.x * s, self.y * s)
    }
}

/// A [`Pose2`] ready to map points ([`Pose2::placement`]): [`Pose2::transform`]'s results
/// without its two trigonometric calls a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    sin: f32,
    cos: f32,
    x: f32,
    y: f32,
}

impl Placement {
    /// Maps a point from the pose's frame into the parent frame.
    pub fn transform(self, p: Vec2) -> Vec2 {
        let (s, c) = (self.sin, self.cos);
        Vec2::new(c * p.x - s * p.y + self.x, s * p.x + c * p.y + self.y)
    }
}

/// A rigid motion in the plane: rotate by `theta`, then translate by (x, y).
///
/// Used both as a pose (the body frame expressed in the world frame) and as the relative
/// motion between two scans; `a.compose(b)` is `a * b` in SE(2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2 {
    pub x: f32,
    pub y: f32,
    pub theta: f32,
}

impl Pose2 {
    pub const IDENTITY: Pose2 = Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    pub fn new(x: f32, y: f32, theta: f32) -> Self {
        Self {
            x,
            y,
            theta: normalize_angle(theta),
        }
    }

    pub fn translation(self) -> Vec2 {
        Vec2::new(self.x, self.y)
    }

    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }

    /// Maps a point from this pose's frame into the parent frame.
    pub fn transform(self, p: Vec2) -> Vec2 {
        self.placement().transform(p)
    }

    /// The pose with its sine and cosine worked out once, to map many points.
    pub fn placement(self) -> Placement {
        Placement {
            sin: sinf(self.theta),
            cos: cosf(self.theta),
            x: self.x,
            y: self.y,
        }
    }

    /// Rotates a direction into the parent frame (no translation).
    pub fn rotate(self, v: Vec2) -> Vec2 {
        let (s, c) = (sinf(self.theta), cosf(self.theta));
        Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    pub fn compose(self, o: Pose2) -> Pose2 {
        let t = self.transform(o.translation());
        Pose2::new(t.x, t.y, self.theta + o.theta)
    }

    pub fn inverse(self) -> Pose2 {
        let (s, c) = (sinf(self.theta), cosf(self.theta));
        Pose2::new(
            -(c * self.x + s * self.y),
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// The motion from `self` to `other`, expressed in the frame of `self`: `inverse(self) * other`.
    pub fn between(self, other: Pose2) -> Pose2 {
        self.inverse().compose(other)
    }

    /// How far apart two poses are: (translation distance m, absolute rotation rad).
    pub fn distance_to(self, o: Pose2) -> (f32, f32) {
        let d = self.between(o);
        (d.translation().norm(), normalize_angle(d.theta).abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;
    use proptest::prelude::*;

    fn close(a: Pose2, b: Pose2) -> bool {
        (a.x - b.x).abs() < 1e-3
            && (a.y - b.y).abs() < 1e-3
            && normalize_angle(a.theta - b.theta).abs() < 1e-4
    }

    #[test]
    fn normalize_keeps_pi_and_maps_minus_pi_to_pi() {
        assert_eq!(normalize_angle(PI), PI);
        assert!((normalize_angle(-PI) - PI).abs() < 1e-6);
        assert!((normalize_angle(3.0 * PI) - PI).abs() < 1e-5);
        assert!((normalize_angle(0.5) - 0.5).abs() < 1e-7);
    }

    #[test]
    fn quarter_turn_maps_x_axis_to_y_axis() {
        let p = Pose2::new(1.0, 2.0, PI / 2.0);
        let q = p.transform(Vec2::new(1.0, 0.0));
        assert!((q.x - 1.0).abs() < 1e-6 && (q.y - 3.0).abs() < 1e-6);
    }

    fn pose() -> impl Strategy<Value = Pose2> {
        (-50.0f32..50.0, -50.0f32..50.0, -3.1f32..3.1).prop_map(|(x, y, t)| Pose2::new(x, y, t))
    }

    proptest! {
        #[test]
        fn normalized_angles_lie_in_half_open_interval(a in -100.0f32..100.0) {
            let n = normalize_angle(a);
            prop_assert!(n > -PI && n <= PI + 1e-6);
            prop_assert!((libm::sinf(n) - libm::sinf(a)).abs() < 1e-3);
        }

        #[test]
        fn inverse_composes_to_identity(p in pose()) {
            prop_assert!(close(p.compose(p.inverse()), Pose2::IDENTITY));
            prop_assert!(close(p.inverse().compose(p), Pose2::IDENTITY));
        }

        #[test]
        fn composition_is_associative(a in pose(), b in pose(), c in pose()) {
            let l = a.compose(b).compose(c);
            let r = a.compose(b.compose(c));
            prop_assert!((l.x - r.x).abs() < 1e-2 && (l.y - r.y).abs() < 1e-2);
            prop_assert!(normalize_angle(l.theta - r.theta).abs() < 1e-4);
        }

        #[test]
        fn between_recovers_the_relative_motion(a in pose(), d in pose()) {
            let b = a.compose(d);
            let back = a.between(b);
            prop_assert!((back.x - d.x).abs() < 1e-2 && (back.y - d.y).abs() < 1e-2);
            prop_assert!(normalize_angle(back.theta - d.theta).abs() < 1e-4);
        }

        #[test]
        fn transform_preserves_distances(p in pose(), ax in -10.0f32..10.0, ay in -10.0f32..10.0,
                                         bx in -10.0f32..10.0, by in -10.0f32..10.0) {
            let (a, b) = (Vec2::new(ax, ay), Vec2::new(bx, by));
            let d0 = (a - b).norm();
            let d1 = (p.transform(a) - p.transform(b)).norm();
            prop_assert!((d0 - d1).abs() < 1e-3);
        }
    }
}
