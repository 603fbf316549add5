//! The nearest reference point in a search window: the rule ([`argmin`]) and, for the default
//! window of six points (three a side) that every association pass searches once per point,
//! the same rule in four-lane SIMD ([`nearest_of_six`]).
//!
//! Written with scalars, the six distances and their argmin came out as two-lane code and a
//! chain of compares and moves (about 80 instructions); in lanes they are two vectors of four
//! (points 0-3 and 2-5, overlapping so that no lane needs masking), a lanewise minimum and a
//! compare against it (under 50).

use crate::geom::Vec2;
use wide::{f32x4, CmpEq, CmpGt, CmpLe};

/// The cross and dot products of `before` and `at` with `q` (`[cross before, cross at, dot
/// before, dot at]`, rounded exactly as [`Vec2::cross`] and [`Vec2::dot`] round them), and the
/// mask of those above zero: a step of the projection's walk (`PreparedScan::walk`).
#[inline(always)]
pub fn crosses_dots(before: Vec2, at: Vec2, q: Vec2) -> (f32x4, i32) {
    let xy = f32x4::new([before.x, before.y, at.x, at.y]);
    let a = (xy * f32x4::new([q.y, q.x, q.y, q.x])).to_array();
    let b = (xy * f32x4::new([q.x, q.y, q.x, q.y])).to_array();
    // x qy - y qx and x qx + y qy (as x qx - -(y qy), which rounds the same).
    let v = f32x4::new([a[0], a[2], b[0], b[2]]) - f32x4::new([a[1], a[3], -b[1], -b[3]]);
    (v, v.cmp_gt(f32x4::splat(0.0)).move_mask())
}

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

/// The usual query of a pass that projects, in one go: `Some((k, nearest))` when the
/// projection's walk from `hint` stops within a step of `hint + 1`, so that
/// `PreparedScan::project` answers `k`, and the default window around `k` (three points a side)
/// lies inside the scan, where `PreparedScan::nearest_in_window` answers `nearest`. `None`
/// otherwise: ask those two. Spares the usual query their bounds checks and branches (about 50
/// of its 130 instructions).
#[inline(always)]
pub fn usual_query(points: &[Vec2], q: Vec2, hint: usize) -> Option<(usize, Option<usize>)> {
    usual_window(points, q, hint).map(|(k, window)| (k, nearest_around(window, k, q)))
}

/// The projection of [`usual_query`] and the default window around it: `Some((k, window))`
/// when the projection's walk from `hint` stops within a step of `hint + 1`, so that
/// `PreparedScan::project` answers `k`, and the six points around `k` lie inside the scan.
///
/// The walk stops at `k` when point `k - 1` is below the bearing of `q`, point `k` is not, and
/// both are within a quarter turn of `q` (`crosses_dots` mask `0b1101`), and it gets there
/// from `hint` when `k = hint + 1` (the usual case: queries come a beam apart), when
/// `k = hint` (the walk's first step does not move up: point `hint` is not below `q`), or when
/// `k = hint + 2` (it moves up twice: points `hint` and `hint + 1` are below `q`).
#[inline(always)]
pub fn usual_window(points: &[Vec2], q: Vec2, hint: usize) -> Option<(usize, &[Vec2; 6])> {
    let stop = |k: usize| {
        let window = six_around(points, k)?;
        let (_, positive) = crosses_dots(window[2], window[3], q);
        Some((positive, window))
    };
    let (positive, window) = stop(hint + 1)?;
    let k = match positive {
        0b1101 => return Some((hint + 1, window)),
        m if m & 0b01 == 0 => hint,
        m if m & 0b11 == 0b11 => hint + 2,
        _ => return None,
    };
    let (positive, window) = stop(k)?;
    (positive == 0b1101).then_some((k, window))
}

/// The default search window around `k` (points `k - 3` to `k + 2`), when it lies inside
/// `points`.
#[inline(always)]
pub fn six_around(points: &[Vec2], k: usize) -> Option<&[Vec2; 6]> {
    points.get(k.wrapping_sub(3)..k + 3)?.try_into().ok()
}

/// The index of the point nearest to `q` in `window`, the six points around `k`.
#[inline(always)]
pub fn nearest_around(window: &[Vec2; 6], k: usize, q: Vec2) -> Option<usize> {
    nearest_of_six(window, q).map(|(j, _)| k - 3 + j)
}

/// Index and squared distance of the point of `window` nearest to `q` by [`argmin`]'s rule,
/// distances rounded as `(p - q).norm_squared()` rounds them.
#[inline(always)]
pub fn nearest_of_six(window: &[Vec2; 6], q: Vec2) -> Option<(usize, f32)> {
    let (low, high) = six_squares(window, q);
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

/// Whether the point of `window` nearest to `q` by [`nearest_of_six`] is within `r2`
/// (squared), without finding it: whether any of the six squared distances, rounded as
/// [`nearest_of_six`] rounds them, is finite and at most `r2`. The least of them is at most
/// `r2` exactly when one of them is, and a NaN distance, which that search passes over, fails
/// the comparison. About half the work of the search, which a count of hits does not need.
#[inline(always)]
pub fn any_within_six(window: &[Vec2; 6], q: Vec2, r2: f32) -> bool {
    // A search that finds nothing finite says no even to an infinite radius.
    let r2 = f32x4::splat(if r2 == f32::INFINITY { f32::MAX } else { r2 });
    let (low, high) = six_squares(window, q);
    (low.cmp_le(r2) | high.cmp_le(r2)).move_mask() != 0
}

/// The squared distances from `q` of the points of `window`, rounded as
/// `(p - q).norm_squared()` rounds them: points 0-3 and points 2-5.
#[inline(always)]
fn six_squares(window: &[Vec2; 6], q: Vec2) -> (f32x4, f32x4) {
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
    (sums(s01, s23), sums(s23, s45))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::PreparedScan;
    use crate::scan::{Beam, Scan};
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

    proptest! {
        /// The yes or no of a count of hits is the search's answer compared with the radius:
        /// over NaN, infinite and overflowing distances and radii of zero, NaN and infinity.
        #[test]
        fn any_within_answers_as_the_nearest_compared(
            xy in proptest::collection::vec((coordinate(), coordinate()), 6),
            qx in coordinate(), qy in coordinate(),
            r2 in prop_oneof![4 => 0.0f32..50.0, 1 => Just(0.0f32), 1 => Just(f32::INFINITY), 1 => Just(f32::NAN)],
        ) {
            let window: [Vec2; 6] = core::array::from_fn(|j| Vec2::new(xy[j].0, xy[j].1));
            let q = Vec2::new(qx, qy);
            let searched = nearest_of_six(&window, q).is_some_and(|(_, d2)| d2 <= r2);
            prop_assert_eq!(any_within_six(&window, q, r2), searched);
        }
    }

    /// A room seen at 1 degree, with a run of beams missing (a gap the walk must cross).
    fn room(ranges: &[f32]) -> PreparedScan<360> {
        let mut s: Scan<360> = Scan::new(0.0);
        for (i, &r) in ranges.iter().enumerate() {
            let a = (-180.0f32 + i as f32).to_radians();
            let beam = if (100..110).contains(&i) {
                Beam::invalid(a)
            } else {
                Beam::new(a, r)
            };
            s.push(beam).unwrap();
        }
        let mut p = PreparedScan::default();
        p.load(&s).unwrap();
        p
    }

    proptest! {
        /// Where the usual queries answer, they answer what the projection and the window
        /// search answer (from hints at, before and after the projection's answer, on points in
        /// angular order and, past a wall's end, not).
        #[test]
        fn the_usual_query_answers_as_the_projection_and_window_search(
            ranges in proptest::collection::vec(0.3f32..8.0, 360),
            beam in 0.0f32..360.0, range in 0.2f32..9.0, offset in -3isize..3,
        ) {
            let p = room(&ranges);
            let a = (-180.0f32 + beam).to_radians();
            let q = Vec2::new(range * libm::cosf(a), range * libm::sinf(a));
            let near = p.project(q, 0).unwrap_or(0) as isize;
            let hint = (near + offset).clamp(0, p.len() as isize) as usize;
            if let Some((k, nearest)) = usual_query(p.points(), q, hint) {
                prop_assert_eq!(p.project(q, hint), Some(k));
                prop_assert_eq!(p.nearest_in_window(q, k, 3).map(|(j, _)| j), nearest);
            }
            // A later pass's search around an old partner (the hint here).
            if let Some(window) = six_around(p.points(), hint) {
                let searched = p.nearest_in_window(q, hint, 3).map(|(j, _)| j);
                prop_assert_eq!(nearest_around(window, hint, q), searched);
            }
        }
    }

    #[test]
    fn the_usual_query_answers_from_a_step_either_side() {
        let p = room(&[2.0; 360]);
        // A third of a degree past the beam at 20 degrees: projects to the next beam from the
        // one before, and is nearer the one before.
        let a = 20.3f32.to_radians();
        let q = Vec2::new(2.0 * libm::cosf(a), 2.0 * libm::sinf(a));
        let k = p.project(q, 0).unwrap();
        for hint in [k - 2, k - 1, k] {
            assert_eq!(usual_query(p.points(), q, hint), Some((k, Some(k - 1))));
        }
        // Not from three points back (the general walk's business).
        assert_eq!(usual_query(p.points(), q, k - 3), None);
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
