//! The few small dense solves the matchers need, in closed form (no allocation, no pivoting
//! tables): 2x2 symmetric eigen-decomposition and a damped 3x3 symmetric solve.

use crate::geom::Vec2;
use wide::{f32x4, CmpGe, CmpGt, CmpLe};

/// Eigen-decomposition of `[[a, b], [b, c]]`: `(lambda_max, lambda_min, unit eigenvector of
/// lambda_min)`. One lane of [`sym2_eigen_lanes`], so a line fitted four at a time and one
/// fitted alone (the local map's cells, the tests' fits by definition) get the same bits.
pub fn sym2_eigen(a: f32, b: f32, c: f32) -> (f32, f32, Vec2) {
    let (hi, lo, x, y) = sym2_eigen_lanes(f32x4::splat(a), f32x4::splat(b), f32x4::splat(c));
    let lane = |v: f32x4| v.to_array()[0];
    (lane(hi), lane(lo), Vec2::new(lane(x), lane(y)))
}

/// [`sym2_eigen`] of four matrices at once, one per lane: `(lambda_max, lambda_min, eigenvector
/// of lambda_min as x and y lanes)`. Of the two algebraically equal eigenvector candidates the
/// longer, numerically safe one is kept; a zero matrix or a multiple of the identity gets an
/// axis. Choices are masks instead of branches.
#[inline(always)]
pub fn sym2_eigen_lanes(a: f32x4, b: f32x4, c: f32x4) -> (f32x4, f32x4, f32x4, f32x4) {
    let half = f32x4::splat(0.5);
    let mean = half * (a + c);
    let half_diff = half * (a - c);
    let radius = (half_diff * half_diff + b * b).sqrt();
    let (hi, lo) = (mean + radius, mean - radius);
    // v1 = (b, lo - a), v2 = (lo - c, b), the longer kept, squared norms summed as `Vec2` does.
    let (v1y, v2x) = (lo - a, lo - c);
    let (norm1, norm2) = (b * b + v1y * v1y, v2x * v2x + b * b);
    let first = norm1.cmp_ge(norm2);
    let (vx, vy) = (first.blend(b, v2x), first.blend(v1y, b));
    let norm = first.blend(norm1, norm2).sqrt();
    let inv = f32x4::ONE / norm;
    let unit = norm.cmp_gt(f32x4::ZERO);
    // Isotropic (a zero matrix or a multiple of the identity): an axis, as the scalar version.
    let x_axis = a.cmp_le(c);
    let dir_x = unit.blend(vx * inv, x_axis.blend(f32x4::ONE, f32x4::ZERO));
    let dir_y = unit.blend(vy * inv, x_axis.blend(f32x4::ZERO, f32x4::ONE));
    (hi, lo, dir_x, dir_y)
}

/// A symmetric 3x3 matrix stored by its upper triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sym3 {
    pub xx: f32,
    pub xy: f32,
    pub xt: f32,
    pub yy: f32,
    pub yt: f32,
    pub tt: f32,
}

impl Sym3 {
    /// Adds `w * j jᵀ`.
    pub fn add_outer(&mut self, j: [f32; 3], w: f32) {
        self.xx += w * j[0] * j[0];
        self.xy += w * j[0] * j[1];
        self.xt += w * j[0] * j[2];
        self.yy += w * j[1] * j[1];
        self.yt += w * j[1] * j[2];
        self.tt += w * j[2] * j[2];
    }

    /// From a full symmetric matrix (its upper triangle is read).
    pub fn from_array(m: [[f32; 3]; 3]) -> Self {
        Self {
            xx: m[0][0],
            xy: m[0][1],
            xt: m[0][2],
            yy: m[1][1],
            yt: m[1][2],
            tt: m[2][2],
        }
    }

    pub fn plus(&self, o: &Sym3) -> Sym3 {
        Sym3 {
            xx: self.xx + o.xx,
            xy: self.xy + o.xy,
            xt: self.xt + o.xt,
            yy: self.yy + o.yy,
            yt: self.yt + o.yt,
            tt: self.tt + o.tt,
        }
    }

    pub fn scaled(&self, k: f32) -> Sym3 {
        Sym3 {
            xx: k * self.xx,
            xy: k * self.xy,
            xt: k * self.xt,
            yy: k * self.yy,
            yt: k * self.yt,
            tt: k * self.tt,
        }
    }

    /// The translation direction this information barely pins down once rotation is free (a
    /// corridor's axis), with the information along the best-pinned direction: `Some` when
    /// least over most is below `ratio`.
    pub fn weak_translation(&self, ratio: f32) -> Option<(f32, Vec2)> {
        let (a, b, c) = self.translation_schur();
        let (hi, lo, v) = sym2_eigen(a, b, c);
        (hi > 0.0 && lo < ratio * hi).then_some((hi, v))
    }

    pub fn to_array(self) -> [[f32; 3]; 3] {
        [
            [self.xx, self.xy, self.xt],
            [self.xy, self.yy, self.yt],
            [self.xt, self.yt, self.tt],
        ]
    }

    fn det(&self) -> f32 {
        self.xx * (self.yy * self.tt - self.yt * self.yt)
            - self.xy * (self.xy * self.tt - self.yt * self.xt)
            + self.xt * (self.xy * self.yt - self.yy * self.xt)
    }

    /// The inverse by the adjugate, or `None` when (numerically) singular.
    pub fn inverse(&self) -> Option<Sym3> {
        let d = self.det();
        let scale = self.xx.abs() + self.yy.abs() + self.tt.abs();
        if !(d.is_finite() && d.abs() > 1e-12 * scale * scale * scale) {
            return None;
        }
        let inv = 1.0 / d;
        Some(Sym3 {
            xx: (self.yy * self.tt - self.yt * self.yt) * inv,
            xy: (self.xt * self.yt - self.xy * self.tt) * inv,
            xt: (self.xy * self.yt - self.xt * self.yy) * inv,
            yy: (self.xx * self.tt - self.xt * self.xt) * inv,
            yt: (self.xt * self.xy - self.xx * self.yt) * inv,
            tt: (self.xx * self.yy - self.xy * self.xy) * inv,
        })
    }

    pub fn mul(&self, v: [f32; 3]) -> [f32; 3] {
        [
            self.xx * v[0] + self.xy * v[1] + self.xt * v[2],
            self.xy * v[0] + self.yy * v[1] + self.yt * v[2],
            self.xt * v[0] + self.yt * v[1] + self.tt * v[2],
        ]
    }

    /// The translation block with rotation eliminated (Schur complement): how well x/y are
    /// pinned down once the best rotation is allowed for.
    pub fn translation_schur(&self) -> (f32, f32, f32) {
        if self.tt <= 0.0 {
            return (self.xx, self.xy, self.yy);
        }
        let k = 1.0 / self.tt;
        (
            self.xx - self.xt * self.xt * k,
            self.xy - self.xt * self.yt * k,
            self.yy - self.yt * self.yt * k,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn eigenvector_satisfies_its_equation(a in -10.0f32..10.0, b in -10.0f32..10.0, c in -10.0f32..10.0) {
            let (hi, lo, v) = sym2_eigen(a, b, c);
            prop_assert!(hi >= lo);
            let av = Vec2::new(a * v.x + b * v.y, b * v.x + c * v.y);
            let tol = 1e-3 * (1.0 + a.abs() + b.abs() + c.abs());
            prop_assert!((av.x - lo * v.x).abs() < tol && (av.y - lo * v.y).abs() < tol);
            prop_assert!((v.norm() - 1.0).abs() < 1e-4);
        }

        #[test]
        fn inverse_times_matrix_is_identity(j in proptest::collection::vec((-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0), 4..8)) {
            let mut m = Sym3::default();
            for (a, b, c) in j { m.add_outer([a, b, c], 1.0); }
            m.xx += 0.5; m.yy += 0.5; m.tt += 0.5;
            let inv = m.inverse().unwrap();
            for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                let back = m.mul(inv.mul(e));
                for k in 0..3 { prop_assert!((back[k] - e[k]).abs() < 2e-3, "{:?} {:?}", back, e); }
            }
        }
    }

    /// Entries that make the awkward cases likely: zeros (axis-aligned and zero matrices),
    /// equal diagonals (isotropic when the off-diagonal is zero too), tiny off-diagonals.
    fn entry() -> impl Strategy<Value = f32> {
        prop_oneof![Just(0.0f32), Just(1.0f32), -1e-6f32..1e-6, -10.0f32..10.0,]
    }

    proptest! {
        /// Each lane of the four-lane decomposition is its own matrix's answer, bit for bit (the
        /// scalar function is one lane of a splat), for lanes that mix near-isotropic,
        /// axis-aligned and general matrices: no lane takes another's candidate or axis.
        #[test]
        fn eigen_lanes_equal_the_scalar_eigen(m in proptest::array::uniform4((entry(), entry(), entry(), any::<bool>()))) {
            // Half the lanes isotropic-ish: c a hair from a.
            let c: [f32; 4] = core::array::from_fn(|l| if m[l].3 { m[l].0 + m[l].2 * 1e-6 } else { m[l].2 });
            let lanes = |f: fn(&(f32, f32, f32, bool)) -> f32| f32x4::from(core::array::from_fn::<f32, 4, _>(|l| f(&m[l])));
            let (hi, lo, x, y) = sym2_eigen_lanes(lanes(|e| e.0), lanes(|e| e.1), f32x4::from(c));
            let (hi, lo, x, y) = (hi.to_array(), lo.to_array(), x.to_array(), y.to_array());
            for l in 0..4 {
                let (shi, slo, v) = sym2_eigen(m[l].0, m[l].1, c[l]);
                for (lane, scalar) in [(hi[l], shi), (lo[l], slo), (x[l], v.x), (y[l], v.y)] {
                    prop_assert_eq!(lane.to_bits(), scalar.to_bits(), "lane {}: {:?} {}", l, m[l], c[l]);
                }
            }
        }
    }

    #[test]
    fn singular_matrix_has_no_inverse() {
        let mut m = Sym3::default();
        m.add_outer([1.0, 0.0, 0.0], 1.0);
        assert!(m.inverse().is_none());
    }
}
