//! The error of one edge and its analytic Jacobians.
//!
//! Following Grisetti, Kümmerle, Stachniss and Burgard, "A tutorial on graph-based SLAM"
//! (IEEE ITS Magazine 2010), section IV: the error is the measured pose of `to` in the frame of
//! `from`, compared with the one the current poses predict, and the poses are updated
//! additively in (x, y, theta) with the heading wrapped afterwards. In SE(2) this is exact
//! enough (the heading is one angle), and it keeps the Jacobians to a few products.

use super::pose::Pose2d;
use plumbline_core::geom::normalize_angle_f64;

pub type Vec3 = [f64; 3];
pub type Mat3 = [[f64; 3]; 3];

/// Error `e = t2v(Z^-1 (X_i^-1 X_j))`, wrapped heading, with `A = de/dx_i` and `B = de/dx_j`.
pub struct Linearized {
    pub error: Vec3,
    pub d_from: Mat3,
    pub d_to: Mat3,
}

/// `e = [R_z^T (R_i^T (t_j - t_i) - t_z); theta_j - theta_i - theta_z]` and its Jacobians.
pub fn linearize(from: Pose2d, to: Pose2d, measurement: Pose2d) -> Linearized {
    let (si, ci) = from.theta.sin_cos();
    let (sz, cz) = measurement.theta.sin_cos();
    let (dx, dy) = (to.x - from.x, to.y - from.y);
    // R_i^T (t_j - t_i): the translation of `to` seen from `from`.
    let (lx, ly) = (ci * dx + si * dy, -si * dx + ci * dy);
    let (ex, ey) = (lx - measurement.x, ly - measurement.y);
    let error = [
        cz * ex + sz * ey,
        -sz * ex + cz * ey,
        normalize_angle_f64(to.theta - from.theta - measurement.theta),
    ];
    // R_z^T R_i^T = R(-(theta_i + theta_z)).
    let (s, c) = (from.theta + measurement.theta).sin_cos();
    let rt = [[c, s], [-s, c]];
    // d(R_i^T)/d theta_i (t_j - t_i) = (ly, -lx); then rotated by R_z^T.
    let (gx, gy) = (ly, -lx);
    let d_theta = [cz * gx + sz * gy, -sz * gx + cz * gy];
    let d_from = [
        [-rt[0][0], -rt[0][1], d_theta[0]],
        [-rt[1][0], -rt[1][1], d_theta[1]],
        [0.0, 0.0, -1.0],
    ];
    let d_to = [
        [rt[0][0], rt[0][1], 0.0],
        [rt[1][0], rt[1][1], 0.0],
        [0.0, 0.0, 1.0],
    ];
    Linearized {
        error,
        d_from,
        d_to,
    }
}

/// `e^T Omega e`: the squared Mahalanobis length of an error.
pub fn chi2(error: &Vec3, information: &Mat3) -> f64 {
    let mut sum = 0.0;
    for r in 0..3 {
        for c in 0..3 {
            sum += error[r] * information[r][c] * error[c];
        }
    }
    sum
}

/// `A^T M` for 3x3 matrices.
pub fn transpose_mul(a: &Mat3, m: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[k][r] * m[k][c]).sum();
        }
    }
    out
}

/// `A B` for 3x3 matrices.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    out
}

/// `M v`.
pub fn mul_vec(m: &Mat3, v: &Vec3) -> Vec3 {
    core::array::from_fn(|r| (0..3).map(|k| m[r][k] * v[k]).sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pose() -> impl Strategy<Value = Pose2d> {
        (-20.0..20.0f64, -20.0..20.0f64, -3.1..3.1f64).prop_map(|(x, y, t)| Pose2d::new(x, y, t))
    }

    /// Central differences of the error under an additive step of one coordinate.
    fn numeric(from: Pose2d, to: Pose2d, z: Pose2d, of_to: bool) -> Mat3 {
        let h = 1e-6;
        let mut out = [[0.0; 3]; 3];
        for k in 0..3 {
            let step = |sign: f64| {
                let mut p = if of_to { to } else { from };
                match k {
                    0 => p.x += sign * h,
                    1 => p.y += sign * h,
                    _ => p.theta += sign * h,
                }
                let (f, t) = if of_to { (from, p) } else { (p, to) };
                linearize(f, t, z).error
            };
            let (plus, minus) = (step(1.0), step(-1.0));
            for (r, row) in out.iter_mut().enumerate() {
                row[k] = normalize_angle_f64(plus[r] - minus[r]) / (2.0 * h);
            }
        }
        out
    }

    proptest! {
        #[test]
        fn jacobians_match_numeric_differentiation(a in pose(), b in pose(), z in pose()) {
            let lin = linearize(a, b, z);
            for (analytic, of_to) in [(lin.d_from, false), (lin.d_to, true)] {
                let num = numeric(a, b, z, of_to);
                for r in 0..3 {
                    for c in 0..3 {
                        prop_assert!((analytic[r][c] - num[r][c]).abs() < 1e-5,
                            "d{}[{r}][{c}]: analytic {} numeric {}",
                            if of_to { "to" } else { "from" }, analytic[r][c], num[r][c]);
                    }
                }
            }
        }

        #[test]
        fn error_vanishes_at_the_measured_pose(a in pose(), z in pose()) {
            let e = linearize(a, a.compose(z), z).error;
            prop_assert!(e.iter().all(|v| v.abs() < 1e-9), "{e:?}");
        }
    }
}
