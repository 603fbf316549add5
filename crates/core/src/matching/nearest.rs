//! Where a query point falls in a scan's angular order ([`PreparedScan::project`]) and which
//! of the points around that place is nearest it ([`PreparedScan::nearest_in_window`]): the
//! search of every association pass. Bearings let a query be projected into the reference's
//! angular order, so a correspondence costs a few comparisons in a window instead of a search
//! over the whole scan (O(N·w), never O(N²)). The window's four-lane arithmetic is in
//! [`super::window`].

use super::prepared::PreparedScan;
use crate::fast_math::atan2_approx;
use crate::geom::Vec2;
use core::f32::consts::TAU;

impl<const N: usize> PreparedScan<N> {
    /// The point `offset` places away in angular order, wrapping on a full circle.
    pub fn neighbour(&self, i: usize, offset: isize) -> Option<usize> {
        self.wrap(i as isize + offset)
    }

    /// Index `j` if it is in the scan, or its wrapped twin on a full circle.
    fn wrap(&self, j: isize) -> Option<usize> {
        if (0..self.len as isize).contains(&j) {
            Some(j as usize)
        } else if self.full_circle && self.len > 0 {
            Some(j.rem_euclid(self.len as isize) as usize)
        } else {
            None
        }
    }

    /// Index of the first point whose bearing is not below the bearing of `q`, searching from
    /// `hint` (queries come in angular order, so this is usually a step or two). `None` when `q`
    /// lies outside the field of view of a scan that is not a full circle.
    #[inline]
    pub fn project(&self, q: Vec2, hint: usize) -> Option<usize> {
        self.walk(q, hint)
            .or_else(|| self.project_by_bearing(q, hint))
    }

    /// [`Self::project`] without any trigonometry, for a query near the hint: a reference
    /// point's bearing is below that of `q` exactly when `q` is counter-clockwise of it (their
    /// cross product is positive) while the two are less than a half turn apart. `None` (ask
    /// [`Self::project_by_bearing`]) when the walk gets long, reaches an end of the scan, or ends
    /// between two points that are not both within a quarter turn of `q`.
    ///
    /// A step looks at the points either side of `k`, their cross and dot products with `q`
    /// in one four-lane vector ([`super::window::crosses_dots`]). Queries come one beam apart,
    /// so the walk usually moves up once and stops: the pair the second step looks at also
    /// tells whether the first moves up, and one vector does both.
    #[inline(always)]
    fn walk(&self, q: Vec2, hint: usize) -> Option<usize> {
        use wide::{f32x4, CmpGe};
        let p = &self.points[..self.len];
        let zero = f32x4::splat(0.0);
        // Cross and dot products of the points before and at `k`, and which are positive.
        let pair = |k: usize| {
            let [before, at] = *<&[Vec2; 2]>::try_from(p.get(k.wrapping_sub(1)..=k)?).ok()?;
            Some(super::window::crosses_dots(before, at, q))
        };
        // Both points of the last pair within a quarter turn of `q`.
        let ahead = |positive: i32| positive & 0b1100 == 0b1100;
        let (mut k, mut steps) = (hint, 8);
        // The first step (whose pair is `hint - 1, hint`) moves up when `hint` is below `q`.
        if hint > 0 {
            if let Some((_, positive)) = pair(hint + 1).filter(|&(_, m)| m & 0b01 != 0) {
                if positive & 0b10 == 0 {
                    return ahead(positive).then_some(hint + 1);
                }
                (k, steps) = (hint + 2, 6);
            }
        }
        for _ in 0..steps {
            let (crosses_dots, positive) = pair(k)?;
            if positive & 0b10 != 0 {
                k += 1;
            } else if zero.cmp_ge(crosses_dots).move_mask() & 0b01 != 0 {
                k -= 1;
            } else {
                return ahead(positive).then_some(k);
            }
        }
        None
    }

    /// [`Self::project`] from the bearing of `q` (an approximate atan2): a short walk from the
    /// hint, or bisection. Out of line: most queries never need it.
    #[inline(never)]
    fn project_by_bearing(&self, q: Vec2, hint: usize) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        let b = &self.bearings[..self.len];
        // Bring the bearing into [a0 - margin, a0 - margin + 2pi), so a point just before the
        // first beam stays just before it instead of wrapping to the far end. atan2 is in
        // (-pi, pi] and the base within a turn of it, so two conditional turns suffice.
        let base = b[0] - self.margin;
        let mut phi = atan2_approx(q.y, q.x) - base;
        if phi < 0.0 {
            phi += TAU;
        }
        if phi < 0.0 {
            phi += TAU;
        }
        if phi >= TAU {
            phi -= TAU;
        }
        phi += base;
        if !self.full_circle && phi > b[self.len - 1] + self.margin {
            return None;
        }
        // Queries arrive in angular order, so a short walk from the last answer usually lands;
        // a jump (a gap in the scan, an occlusion edge) falls back to bisection. On sorted
        // bearings both end where the bearing's place is, from any start, so the walk starts
        // where evenly spaced beams would put it, which also lands after a jump. (Not for a
        // NaN bearing, where the walk stops at once and bisection would say 0.)
        let mut k = if self.sorted && !phi.is_nan() {
            // At least 0 (`as` saturates), at most the end.
            (((phi - b[0]) * 2.0 / self.margin) as usize).min(self.len)
        } else {
            hint.min(self.len)
        };
        for _ in 0..8 {
            if k < self.len && b[k] < phi {
                k += 1;
            } else if k > 0 && b[k - 1] >= phi {
                k -= 1;
            } else {
                return Some(k);
            }
        }
        Some(b.partition_point(|&a| a < phi))
    }

    /// The nearest point to `q` among `half_window` points either side of `k` (from `k -
    /// half_window` to `k + half_window - 1`), with its squared distance. Always inlined: as a
    /// call (the compiler's choice with a plain `#[inline]`) its answer went through memory, about
    /// 12 instructions of a query's ~90.
    #[inline(always)]
    pub fn nearest_in_window(&self, q: Vec2, k: usize, half_window: usize) -> Option<(usize, f32)> {
        // The usual case, inlined into every association: the default window (3 a side) inside
        // the scan, as a fixed-length array searched in four-lane SIMD.
        let six = super::window::six_around(&self.points[..self.len], k);
        match six.filter(|_| half_window == 3) {
            Some(window) => super::window::nearest_of_six(window, q).map(|(j, d2)| (k - 3 + j, d2)),
            None => self.nearest_in_pieces(q, k, half_window),
        }
    }

    /// Whether the point [`Self::nearest_in_window`] finds is within `r2` (squared) of `q`,
    /// with the default window's search cut to that yes or no
    /// ([`super::window::any_within_six`]).
    #[inline(always)]
    pub fn near_in_window(&self, q: Vec2, k: usize, half_window: usize, r2: f32) -> bool {
        let six = super::window::six_around(&self.points[..self.len], k);
        match six.filter(|_| half_window == 3) {
            Some(window) => super::window::any_within_six(window, q, r2),
            None => self
                .nearest_in_pieces(q, k, half_window)
                .is_some_and(|(_, d2)| d2 <= r2),
        }
    }

    /// [`Self::nearest_in_window`] for other window sizes and near an end of the scan: the part
    /// inside the scan and, on a full circle, the parts that wrap.
    #[inline(never)]
    fn nearest_in_pieces(&self, q: Vec2, k: usize, half_window: usize) -> Option<(usize, f32)> {
        let n = self.len as isize;
        let (lo, hi) = (
            k as isize - half_window as isize,
            k as isize + half_window as isize,
        );
        let pieces = if self.full_circle {
            [(lo, hi), (n + lo, n), (0, hi - n)]
        } else {
            [(lo, hi), (0, 0), (0, 0)]
        };
        let mut best: Option<(usize, f32)> = None;
        for (from, to) in pieces {
            let (from, to) = (from.clamp(0, n) as usize, to.clamp(0, n) as usize);
            let piece = self.points[from..to].iter();
            if let Some((j, d2)) = super::window::argmin(piece.map(|p| (*p - q).norm_squared())) {
                if best.is_none_or(|(_, b)| d2 < b) {
                    best = Some((from + j, d2));
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::prepared::tests::wall_scan;
    use crate::scan::{Beam, Scan};

    #[test]
    fn projection_finds_the_beam_with_the_same_bearing() {
        let mut p: PreparedScan<128> = PreparedScan::default();
        p.load(&wall_scan()).unwrap();
        let q = Vec2::new(1.5, 1.5 * libm::tanf(10.5f32.to_radians()));
        // Bearing 10.5 degrees lies between beams at 10 (index 70) and 11 (index 71).
        assert_eq!(p.project(q, 0), Some(71));
        assert_eq!(p.project(q, 120), Some(71));
        // From a nearby hint the cross-product walk answers by itself.
        assert_eq!(p.walk(q, 68), Some(71));
        // Behind the sensor: outside a 120-degree field of view.
        assert_eq!(p.project(Vec2::new(-1.0, 0.1), 0), None);
        // (2, 0.02) is nearer the 1-degree beam (index 61, y = 0.035) than the 0-degree one.
        let (j, _) = p.nearest_in_window(Vec2::new(2.0, 0.02), 60, 3).unwrap();
        assert_eq!(j, 61);
    }

    /// The walk as written with scalars before its steps went into lanes: the rule they keep.
    fn scalar_walk<const N: usize>(s: &PreparedScan<N>, q: Vec2, hint: usize) -> Option<usize> {
        let p = s.points();
        let mut k = hint;
        for _ in 0..8 {
            let (Some(&before), Some(&at)) = (p.get(k.wrapping_sub(1)), p.get(k)) else {
                return None;
            };
            if at.cross(q) > 0.0 {
                k += 1;
            } else if before.cross(q) <= 0.0 {
                k -= 1;
            } else {
                return (at.dot(q) > 0.0 && before.dot(q) > 0.0).then_some(k);
            }
        }
        None
    }

    proptest::proptest! {
        /// The lanes walk exactly as the scalar steps did: from every hint, over points in
        /// angular order and in none (the walk then runs back and forth or out of steps), on
        /// a coarse grid so that zero cross and dot products and ties are common.
        #[test]
        fn the_walk_in_lanes_takes_the_scalar_steps(
            grid in proptest::collection::vec((-4i8..=4, -4i8..=4), 1..24),
            qx in -4i8..=4, qy in -4i8..=4, scale in proptest::prop_oneof![proptest::strategy::Just(1.0f32), 0.01f32..30.0],
            ordered in proptest::bool::ANY,
        ) {
            let mut p: PreparedScan<24> = PreparedScan {
                len: grid.len(),
                ..PreparedScan::default()
            };
            for (point, &(x, y)) in p.points.iter_mut().zip(&grid) {
                *point = Vec2::new(x as f32, y as f32) * scale;
            }
            if ordered {
                p.points[..p.len].sort_by(|a, b| libm::atan2f(a.y, a.x).total_cmp(&libm::atan2f(b.y, b.x)));
            }
            let q = Vec2::new(qx as f32, qy as f32) * scale;
            for hint in 0..=p.len + 1 {
                proptest::prop_assert_eq!(p.walk(q, hint), scalar_walk(&p, q, hint), "hint {}", hint);
            }
        }
    }

    /// [`PreparedScan::project_by_bearing`]'s search of bearings not known to be sorted: a walk
    /// from the hint, or bisection.
    fn search_from_hint<const N: usize>(
        s: &PreparedScan<N>,
        q: Vec2,
        hint: usize,
    ) -> Option<usize> {
        let unknown = PreparedScan {
            sorted: false,
            ..s.clone()
        };
        unknown.project_by_bearing(q, hint)
    }

    proptest::proptest! {
        /// Starting the search of sorted bearings where the bearing puts it lands where the
        /// walk from the hint (or bisection) lands: over scans with gaps and ties, queries
        /// anywhere (past the ends, at the sensor, NaN) and every hint.
        #[test]
        fn the_start_of_a_search_of_sorted_bearings_changes_no_answer(
            beams in proptest::collection::vec((0.0f32..0.1, proptest::bool::weighted(0.7), 0.3f32..6.0), 1..64),
            start in -3.5f32..0.0,
            q in proptest::prop_oneof![
                8 => (-7.0f32..7.0, -7.0f32..7.0),
                1 => proptest::strategy::Just((0.0f32, 0.0f32)),
                1 => proptest::strategy::Just((f32::NAN, 1.0f32)),
            ],
        ) {
            let mut s: Scan<64> = Scan::new(0.0);
            let mut a = start;
            for &(step, valid, r) in &beams {
                a += step;
                s.push(if valid { Beam::new(a, r) } else { Beam::invalid(a) }).unwrap();
            }
            let mut p: PreparedScan<64> = PreparedScan::default();
            p.load(&s).unwrap();
            proptest::prop_assert!(p.sorted);
            let q = Vec2::new(q.0, q.1);
            for hint in 0..=p.len() + 1 {
                proptest::prop_assert_eq!(p.project_by_bearing(q, hint), search_from_hint(&p, q, hint), "hint {}", hint);
            }
        }
    }

    fn ring_scan() -> Scan<360> {
        // A room seen all the way round at 1 degree, ranges varying like walls at mixed distances.
        let mut s = Scan::new(0.0);
        for i in 0..360 {
            let a = (-180.0f32 + i as f32).to_radians();
            s.push(Beam::new(a, 2.0 + libm::sinf(3.0 * a))).unwrap();
        }
        s
    }

    proptest::proptest! {
        /// The trigonometry-free walk must land where the bearing says, from any hint, on an
        /// open field of view and on a full ring (queries kept off exact beam bearings, where
        /// the approximate atan2 may round either way).
        #[test]
        fn projection_by_cross_products_agrees_with_the_bearing(
            beam in 0usize..360, frac in 0.05f32..0.95, range in 0.2f32..20.0, offset in -10isize..10, ring in proptest::bool::ANY,
        ) {
            let mut p: PreparedScan<360> = PreparedScan::default();
            if ring {
                p.load(&ring_scan()).unwrap();
            } else {
                let wall = wall_scan();
                let mut s: Scan<360> = Scan::new(0.0);
                for b in wall.beams() {
                    s.push(*b).unwrap();
                }
                p.load(&s).unwrap();
            }
            let a = (-180.0f32 + beam as f32 + frac).to_radians();
            let q = Vec2::new(range * libm::cosf(a), range * libm::sinf(a));
            // Hints near the answer, where the walk (not the fallback) decides.
            let near = p.project_by_bearing(q, 0).unwrap_or(0) as isize;
            let hint = (near + offset).clamp(0, p.len() as isize) as usize;
            proptest::prop_assert_eq!(p.project(q, hint), p.project_by_bearing(q, hint));
        }
    }
}
