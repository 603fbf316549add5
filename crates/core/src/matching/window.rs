//! The nearest reference point in a search window: the rule ([`argmin`]) and, for the default
//! window of six points (three a side) that every association pass searches once per point,
//! the same rule in four-lane SIMD ([`nearest_of_six`]).
//!
//! Written with scalars, the six distances and their argmin came out as two-lane code and a
//! chain of compares and moves (about 80 instructions); in lanes they are two vectors of four
//! (points 0-3 and 2-5, overlapping so that no lane needs masking), a lanewise minimum and a
//! compare against it (under 50).

use crate::geom::Vec2;
use wide::{f32x4, CmpEq};

/// Index and value of the least of `values` (the first of equals), ignoring NaN and infinity.
#[inline(always)]
pub fn argmin(values: impl Iterator<Item = f32>) -> Option<(usize, f32)> {
    let mut best = (0, f32::INFINITY);
    for (j, d2) in values.enumerate() {
        if d2 < best.1 {
            best = (j, d2);
        }
    }
    (best.1 < f32::INFINITY).then_some(best)
}

/// Index and squared distance of the point of `window` nearest to `q` by [`argmin`]'s rule,
/// distances rounded as `(p - q).norm_squared()` rounds them.
#[inline(always)]
pub fn nearest_of_six(window: &[Vec2; 6], q: Vec2) -> Option<(usize, f32)> {
    let qq = f32x4::new([q.x, q.y, q.x, q.y]);
    let squares = |a: Vec2, b: Vec2| {
        let d = f32x4::new([a.x, a.y, b.x, b.y]) - qq;
        (d * d).to_array()
    };
    let (s01, s23, s45) = (
        squares(window[0], window[1]),
        squares(window[2], window[3]),
        squares(window[4], window[5]),
    );
    // x² + y² of two points from each of two vectors.
    let sums = |a: [f32; 4], b: [f32; 4]| {
        f32x4::new([a[0], a[2], b[0], b[2]]) + f32x4::new([a[1], a[3], b[1], b[3]])
    };
    let (low, high) = (sums(s01, s23), sums(s23, s45));
    // A lanewise minimum may pass over a smaller distance next to a NaN (a NaN only comes from
    // a NaN coordinate: the sum of squares is never infinity minus infinity). Never in a
    // matcher's scans, but the rule is the rule.
    let both = low + high;
    if both.cmp_eq(both).move_mask() != 0b1111 {
        return argmin(window.iter().map(|p| (*p - q).norm_squared()));
    }
    // The least in every lane: of lanes 0 and 2 and of 1 and 3, then of the two.
    let m = low.fast_min(high).to_array();
    let m = f32x4::new(m).fast_min(f32x4::new([m[2], m[3], m[0], m[1]]));
    let m = m.to_array();
    let at = f32x4::new(m).fast_min(f32x4::new([m[1], m[0], m[3], m[2]]));
    let d2 = at.to_array()[0];
    if d2 == f32::INFINITY {
        return None;
    }
    // Points 2 and 3 are in both vectors; either vote finds them first.
    let hits = low.cmp_eq(at).move_mask() | (high.cmp_eq(at).move_mask() << 2);
    Some((hits.trailing_zeros() as usize, d2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn coordinate() -> impl Strategy<Value = f32> {
        // Mostly ordinary, sometimes repeated, huge (distances overflow), infinite or NaN.
        prop_oneof![
            8 => -20.0f32..20.0,
            1 => Just(1.0f32),
            1 => prop_oneof![Just(3e19f32), Just(-3e19), Just(f32::NAN), Just(f32::INFINITY)],
        ]
    }

    proptest! {
        #[test]
        fn lanes_agree_with_the_scalar_rule(
            xy in proptest::collection::vec((coordinate(), coordinate()), 6),
            qx in coordinate(), qy in coordinate(),
        ) {
            let window: [Vec2; 6] = core::array::from_fn(|j| Vec2::new(xy[j].0, xy[j].1));
            let q = Vec2::new(qx, qy);
            let lanes = nearest_of_six(&window, q);
            let scalar = argmin(window.iter().map(|p| (*p - q).norm_squared()));
            prop_assert_eq!(lanes.map(|(j, d)| (j, d.to_bits())), scalar.map(|(j, d)| (j, d.to_bits())));
        }
    }

    #[test]
    fn ties_go_to_the_first_and_nothing_finite_is_none() {
        let q = Vec2::ZERO;
        let mut w = [Vec2::new(1.0, 0.0); 6];
        assert_eq!(nearest_of_six(&w, q), Some((0, 1.0)));
        w[4] = Vec2::new(0.0, 0.5);
        w[5] = Vec2::new(0.5, 0.0);
        assert_eq!(nearest_of_six(&w, q), Some((4, 0.25)));
        // A NaN in the lane beside the least, where a lanewise minimum can lose the least.
        w = [Vec2::new(1.0, 0.0); 6];
        w[0] = Vec2::new(0.5, 0.0);
        w[2] = Vec2::new(f32::NAN, 0.0);
        assert_eq!(nearest_of_six(&w, q), Some((0, 0.25)));
        let far = [Vec2::new(3e19, 0.0); 6];
        assert_eq!(nearest_of_six(&far, q), None);
    }
}
