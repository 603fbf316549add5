//! The few 3-D types the simulator needs, in `f64`: vectors, unit quaternions and principal-axis
//! inertia. Kept local (no nalgebra) so the hot loop stays small and fully inlined.

use core::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A 3-D vector (metres, m/s, rad/s, N ... depending on use).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Vec3 {
    pub const ZERO: Vec3 = Vec3 {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };
    pub const Z: Vec3 = Vec3 {
        x: 0.0,
        y: 0.0,
        z: 1.0,
    };

    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    pub fn dot(self, o: Vec3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// Component-wise product (diagonal matrix times vector).
    pub fn scale(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }

    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f64> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

/// A unit quaternion rotating body (FLU) vectors into the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quat {
    pub w: f64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Default for Quat {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Quat {
    pub const IDENTITY: Quat = Quat {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// ZYX (yaw, then pitch, then roll) Euler angles, REP 103.
    pub fn from_euler(roll: f64, pitch: f64, yaw: f64) -> Quat {
        let (sr, cr) = (roll * 0.5).sin_cos();
        let (sp, cp) = (pitch * 0.5).sin_cos();
        let (sy, cy) = (yaw * 0.5).sin_cos();
        Quat {
            w: cr * cp * cy + sr * sp * sy,
            x: sr * cp * cy - cr * sp * sy,
            y: cr * sp * cy + sr * cp * sy,
            z: cr * cp * sy - sr * sp * cy,
        }
    }

    /// (roll, pitch, yaw) of this rotation, ZYX convention.
    pub fn to_euler(self) -> (f64, f64, f64) {
        let Quat { w, x, y, z } = self;
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        (roll, pitch, yaw)
    }

    pub fn conj(self) -> Quat {
        Quat {
            w: self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }

    /// Rotates a body vector into the world frame.
    pub fn rotate(self, v: Vec3) -> Vec3 {
        let u = Vec3::new(self.x, self.y, self.z);
        let t = u.cross(v) * 2.0;
        v + t * self.w + u.cross(t)
    }

    /// The body x, y and z axes in the world frame (the rotation matrix's columns).
    pub fn axes(self) -> [Vec3; 3] {
        let Quat { w, x, y, z } = self;
        [
            Vec3::new(
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y + w * z),
                2.0 * (x * z - w * y),
            ),
            Vec3::new(
                2.0 * (x * y - w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z + w * x),
            ),
            self.z_axis(),
        ]
    }

    /// The body z axis in the world frame (the thrust direction), cheaper than `rotate(Z)`.
    pub fn z_axis(self) -> Vec3 {
        let Quat { w, x, y, z } = self;
        Vec3::new(
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        )
    }

    /// Rotates a world vector into the body frame.
    pub fn rotate_inv(self, v: Vec3) -> Vec3 {
        self.conj().rotate(v)
    }

    /// Time derivative for body rates `w`: q' = q ⊗ (0, w) / 2, the Hamilton product written
    /// out without the zero scalar part (its products cannot be optimised away: 0 · NaN).
    pub fn derivative(self, w: Vec3) -> Quat {
        let (p, q, r) = (0.5 * w.x, 0.5 * w.y, 0.5 * w.z);
        Quat {
            w: -self.x * p - self.y * q - self.z * r,
            x: self.w * p + self.y * r - self.z * q,
            y: self.w * q - self.x * r + self.z * p,
            z: self.w * r + self.x * q - self.y * p,
        }
    }

    /// `self + d * h`, component-wise (an RK4 stage; renormalised after the full step).
    pub fn add_scaled(self, d: Quat, h: f64) -> Quat {
        Quat {
            w: self.w + d.w * h,
            x: self.x + d.x * h,
            y: self.y + d.y * h,
            z: self.z + d.z * h,
        }
    }

    /// Scaled to unit length (one division, four multiplications: it runs every step).
    pub fn normalized(self) -> Quat {
        let k =
            1.0 / (self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z).sqrt();
        Quat {
            w: self.w * k,
            x: self.x * k,
            y: self.y * k,
            z: self.z * k,
        }
    }

    /// Back to unit length for a quaternion already within a whisker of it (an integrator's
    /// drift): one Newton step for 1/|q|, k = (3 - |q|²) / 2, whose error is of order
    /// (|q|² - 1)², far below rounding here, and which needs no square root or division on
    /// the step's critical path.
    pub fn renormalized(self) -> Quat {
        let n2 = self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z;
        let k = 1.5 - 0.5 * n2;
        Quat {
            w: self.w * k,
            x: self.x * k,
            y: self.y * k,
            z: self.z * k,
        }
    }

    pub fn is_finite(self) -> bool {
        self.w.is_finite() && self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Yaw of the body x axis projected on the world floor plane.
    pub fn yaw(self) -> f64 {
        self.to_euler().2
    }
}

/// Hamilton product: `a * b` applies `b` first, then `a`.
impl Mul for Quat {
    type Output = Quat;

    fn mul(self, o: Quat) -> Quat {
        Quat {
            w: self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            x: self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            y: self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            z: self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip_and_rotation_sense() {
        let q = Quat::from_euler(0.1, -0.2, 2.5);
        let (r, p, y) = q.to_euler();
        assert!((r - 0.1).abs() < 1e-12 && (p + 0.2).abs() < 1e-12 && (y - 2.5).abs() < 1e-12);
        // Yaw +90 degrees turns body x into world y (counter-clockwise).
        let v = Quat::from_euler(0.0, 0.0, core::f64::consts::FRAC_PI_2)
            .rotate(Vec3::new(1.0, 0.0, 0.0));
        assert!((v.x).abs() < 1e-12 && (v.y - 1.0).abs() < 1e-12);
        assert!((q.z_axis() - q.rotate(Vec3::Z)).norm() < 1e-12);
        let [ax, ay, az] = q.axes();
        assert!((ax - q.rotate(Vec3::new(1.0, 0.0, 0.0))).norm() < 1e-12);
        assert!((ay - q.rotate(Vec3::new(0.0, 1.0, 0.0))).norm() < 1e-12);
        assert!((az - q.rotate(Vec3::Z)).norm() < 1e-12);
        let w = Vec3::new(0.4, -1.3, 2.2);
        let d = q.derivative(w);
        let full = q * Quat {
            w: 0.0,
            x: w.x,
            y: w.y,
            z: w.z,
        };
        for (a, b) in [(d.w, full.w), (d.x, full.x), (d.y, full.y), (d.z, full.z)] {
            assert!((a - 0.5 * b).abs() < 1e-15, "q' = q ⊗ (0, w) / 2");
        }
        let drifted = Quat {
            w: q.w * (1.0 + 3e-9),
            ..q
        };
        let (a, b) = (drifted.renormalized(), drifted.normalized());
        for (u, v) in [(a.w, b.w), (a.x, b.x), (a.y, b.y), (a.z, b.z)] {
            assert!((u - v).abs() < 1e-15, "renormalized {a:?} vs {b:?}");
        }
        let back = q.rotate_inv(q.rotate(Vec3::new(0.3, -1.0, 2.0)));
        assert!((back - Vec3::new(0.3, -1.0, 2.0)).norm() < 1e-12);
    }
}
