//! Fast trigonometry for the matcher's hot loops.
//!
//! The bearing only picks a search window a few beams wide, so 1e-4 rad of error is harmless,
//! and libm's exact atan2f would be a third of a match's time. Turning a beam into a point needs
//! a sine and cosine per beam; libm's were an eighth of a 360-beam match, and within the small
//! angles of a scan a plain reduction to a quarter turn is as accurate as f32 allows.

use core::f32::consts::{FRAC_2_PI, FRAC_PI_2, PI};

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
/// [-pi/4, pi/4] and Taylor polynomials that are exact to f32 there.
pub fn sin_cos(a: f32) -> (f32, f32) {
    // Quarter turns to take off, rounded to nearest (half away from zero).
    let k = (a * FRAC_2_PI + if a < 0.0 { -0.5 } else { 0.5 }) as i32;
    // pi/2 in two parts, so r keeps its precision over the quarter turns of a scan.
    const HALF_PI_HI: f32 = 1.570_796_4;
    const HALF_PI_LO: f32 = -4.371_139e-8;
    let r = (a - k as f32 * HALF_PI_HI) - k as f32 * HALF_PI_LO;
    let r2 = r * r;
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0)))));
    let c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0))));
    // Quarter turn k: (s, c), (c, -s), (-s, -c), (-c, s). Selects and sign flips rather than a
    // match, so a loop of calls has no branches and vectorises.
    let odd = k & 1 != 0;
    let (sin, cos) = if odd { (c, s) } else { (s, c) };
    let flip = |v: f32, neg: bool| if neg { -v } else { v };
    (flip(sin, k & 2 != 0), flip(cos, k.wrapping_add(1) & 2 != 0))
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

        #[test]
        fn matches_libm_closely(y in -100.0f32..100.0, x in -100.0f32..100.0) {
            let e = crate::geom::normalize_angle(atan2_approx(y, x) - libm::atan2f(y, x));
            prop_assert!(e.abs() < 2e-5, "y={y} x={x} err={e}");
        }
    }
}
