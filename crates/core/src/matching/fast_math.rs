//! A fast atan2 for choosing where to look in the reference scan.
//!
//! The bearing only picks a search window a few beams wide, so 1e-4 rad of error is harmless,
//! and libm's exact atan2f would be a third of a match's time.

use core::f32::consts::{FRAC_PI_2, PI};

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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_libm_closely(y in -100.0f32..100.0, x in -100.0f32..100.0) {
            let e = crate::geom::normalize_angle(atan2_approx(y, x) - libm::atan2f(y, x));
            prop_assert!(e.abs() < 2e-5, "y={y} x={x} err={e}");
        }
    }
}
