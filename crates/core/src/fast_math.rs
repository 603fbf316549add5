//! Fast trigonometry for hot loops: the matcher's beams and bearings, the attitude filter's
//! Euler angles, the de-skew of every beam.
//!
//! The bearing only picks a search window a few beams wide, so 1e-4 rad of error is harmless,
//! and libm's exact atan2f would be a third of a match's time. Turning a beam into a point needs
//! a sine and cosine per beam; libm's were an eighth of a 360-beam match, and within the small
//! angles of a scan a plain reduction to a quarter turn is as accurate as f32 allows.

use bytemuck::cast;
use core::f32::consts::{FRAC_2_PI, FRAC_PI_2, PI};
use wide::{f32x4, i32x4, CmpEq, CmpLt};

/// atan2 with at most about 1e-5 rad of error (odd minimax polynomial on [0, 1]).
pub fn atan2_approx(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi == 0.0 {
        return 0.0;
    }
    let t = lo / hi;
    let s = t * t;
    let mut r = t
        * (0.999_977_26
            + s * (-0.332_623_47
                + s * (0.193_543_46 + s * (-0.116_432_87 + s * (0.052_653_32 - s * 0.011_721_2)))));
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// `(sin a, cos a)` within about 5e-7 for |a| up to a turn (beam angles), by reduction to
/// [-pi/4, pi/4] and Taylor polynomials that are exact to f32 there. One lane of
/// [`sin_cos_x4`], so a beam's point does not depend on whether it was turned alone or in a
/// group of four.
pub fn sin_cos(a: f32) -> (f32, f32) {
    let (s, c) = sin_cos_x4(f32x4::splat(a));
    (s.to_array()[0], c.to_array()[0])
}

/// [`sin_cos`] of four angles at once. Scan loading turns four beams at a time with it: the
/// compiler's own vectorisation of a scalar loop left the quarter-turn reduction (a conversion
/// and two selects a beam) scalar. Always inlined: left to the compiler, it became a call in
/// scan loading, with its lanes passed through memory, whenever other code changed the
/// inlining budget (about 5 k more instructions a 360-beam match).
#[inline(always)]
pub fn sin_cos_x4(a: f32x4) -> (f32x4, f32x4) {
    let half = a
        .cmp_lt(f32x4::ZERO)
        .blend(f32x4::splat(-0.5), f32x4::splat(0.5));
    // Quarter turns to take off, rounded to nearest (half away from zero; truncation toward
    // zero as `as i32` does, the angles being far inside i32 range).
    let k = (a * f32x4::splat(FRAC_2_PI) + half).trunc_int();
    let kf = f32x4::from_i32x4(k);
    // pi/2 in two parts, so r keeps its precision over the quarter turns of a scan.
    const HALF_PI_HI: f32 = 1.570_796_4;
    const HALF_PI_LO: f32 = -4.371_139e-8;
    let r = (a - kf * f32x4::splat(HALF_PI_HI)) - kf * f32x4::splat(HALF_PI_LO);
    let r2 = r * r;
    let c = |v: f32| f32x4::splat(v);
    let s = r
        * (c(1.0)
            + r2 * (c(-1.0 / 6.0)
                + r2 * (c(1.0 / 120.0) + r2 * (c(-1.0 / 5040.0) + r2 * c(1.0 / 362_880.0)))));
    let co = c(1.0)
        + r2 * (c(-0.5) + r2 * (c(1.0 / 24.0) + r2 * (c(-1.0 / 720.0) + r2 * c(1.0 / 40_320.0))));
    // Quarter turn k: (s, c), (c, -s), (-s, -c), (-c, s), by selects and sign flips. The masks
    // are the lanes where a bit of k is set.
    let bit = |k: i32x4, b: i32| -> f32x4 { cast((k & i32x4::splat(b)).cmp_eq(i32x4::splat(b))) };
    let odd = bit(k, 1);
    let (sin, cos) = (odd.blend(co, s), odd.blend(s, co));
    let flip = |v: f32x4, neg: f32x4| neg.blend(-v, v);
    (flip(sin, bit(k, 2)), flip(cos, bit(k + i32x4::splat(1), 2)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn sin_cos_matches_libm_closely(a in -7.0f32..7.0) {
            let (s, c) = sin_cos(a);
            prop_assert!((s - libm::sinf(a)).abs() < 5e-7, "a={a} sin {s} vs {}", libm::sinf(a));
            prop_assert!((c - libm::cosf(a)).abs() < 5e-7, "a={a} cos {c} vs {}", libm::cosf(a));
        }

        /// Each lane is its own angle's answer (no lane takes another's quarter turn or sign).
        #[test]
        fn each_lane_is_its_own_angles_answer(a in proptest::array::uniform4(-13.0f32..13.0)) {
            let (s, c) = sin_cos_x4(f32x4::from(a));
            for (i, &ai) in a.iter().enumerate() {
                let (si, ci) = sin_cos(ai);
                prop_assert_eq!(s.to_array()[i].to_bits(), si.to_bits(), "sin {}", ai);
                prop_assert_eq!(c.to_array()[i].to_bits(), ci.to_bits(), "cos {}", ai);
            }
        }

        #[test]
        fn matches_libm_closely(y in -100.0f32..100.0, x in -100.0f32..100.0) {
            let e = crate::geom::normalize_angle(atan2_approx(y, x) - libm::atan2f(y, x));
            prop_assert!(e.abs() < 2e-5, "y={y} x={x} err={e}");
        }
    }
}
