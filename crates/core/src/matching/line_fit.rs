//! Local line fits of a reference scan: every point's normal from its angular neighbours, four
//! centres at a time (the lanes are in [`super::fit_lanes`]).

use super::fit_lanes::{fit4, lane, FitLimits, Fits};
use super::prepared::{LineFit, PreparedScan};
use core::ops::Range;
use wide::{f32x4, CmpGt};

impl LineFit {
    /// Four fits' unit normals quantised, lane by lane, and none where a lane is not a line.
    /// Rounds half away from zero; no clamp: a unit vector's component is within a few ulps of
    /// 1, so scaled and rounded it is at most `i16::MAX` in magnitude.
    #[inline(always)]
    fn lines(fits: &Fits) -> [Self; 4] {
        let q = |v: f32x4| {
            let scaled = v * Self::SCALE + f32x4::splat(0.5).copysign(v);
            (scaled & fits.is_line).fast_trunc_int().to_array()
        };
        let (nx, ny) = (q(fits.normal_x), q(fits.normal_y));
        core::array::from_fn(|l| LineFit {
            nx: nx[l] as i16,
            ny: ny[l] as i16,
        })
    }
}

/// Most neighbours on each side a point's line fit takes (the fit normally stops earlier, at
/// its spatial extent). A cap of 4 where beams are 1 degree apart would be faster and better on
/// Intel (near error 2.3 -> 1.5 cm), but makes the normals noisier on 360-beam scans with 2 cm
/// noise (local-map drift test 1.4 -> 2.0 cm).
const LINE_NEIGHBOURS: usize = 8;

/// On scans denser than [`DENSE_BEAM_STEP_RAD`], 8 neighbours are too few: at the URG-04LX's
/// 0.36 degrees they span 5 cm at a metre, under the extent, and with its 1 % range noise most
/// such fits fail the flatness test (a third of the points kept, every match in the recovery
/// search: median 15.6 ms a match in the simulator's room, 53 us with 16). 12 is not enough
/// there (12.5 ms). Sparser scans keep 8: more make the matcher surer of itself than the local
/// map's weighting is tuned for (the synthetic laps' drift 1.4 -> 2.4 cm at 1 degree).
const DENSE_LINE_NEIGHBOURS: usize = 16;

/// Centres whose line fits share one copy of their points (a multiple of 4, the lanes): the
/// copy's `2 * M` points beyond the block's centres are copied again by the next block.
const FIT_BLOCK: usize = 64;

/// Beams closer than this (0.4 degree) make a scan dense: the URG-04LX (0.36), the UTM-30LX
/// (0.25); the 0.5- and 1-degree SICK logs and the XV-11 are not.
const DENSE_BEAM_STEP_RAD: f32 = 0.4 * core::f32::consts::PI / 180.0;

impl<const N: usize> PreparedScan<N> {
    /// Fits a local line to every point from its angular neighbours on each side, walking
    /// outwards until they span `min_extent_m` (or `LINE_NEIGHBOURS` points, 16 on dense scans,
    /// or a neighbour farther than `max_neighbour_m`, a gap). A spatial extent, not a beam count,
    /// is what makes the fit rise above range noise at every beam density; points on clutter or
    /// alone get none.
    ///
    /// Four consecutive points are fitted at once, one per lane ([`fit4`]).
    pub fn fit_lines(&mut self, max_neighbour_m: f32, max_flatness: f32, min_extent_m: f32) {
        let limits = FitLimits {
            max2: max_neighbour_m * max_neighbour_m,
            extent2: min_extent_m * min_extent_m,
            max_flatness,
        };
        // The cap as a constant, so each instance's window and walk have constant bounds (as a
        // run-time value it cost the scalar walk 8 % more instructions a 360-beam match).
        if self.is_dense() {
            self.fit_all::<DENSE_LINE_NEIGHBOURS>(&limits);
        } else {
            self.fit_all::<LINE_NEIGHBOURS>(&limits);
        }
        self.has_lines = true;
    }

    /// [`Self::fit_lines`] with at most `M` neighbours a side: groups of four centres whose
    /// neighbours are all inside the scan, a block of [`FIT_BLOCK`] centres at a time, read
    /// them from a copy of the block's points with x and y apart, so the x (or y) of four
    /// consecutive ones is one load (`wide` has no shuffle to take them out of `Vec2` pairs, and
    /// lanes filled one at a time cost 14 instructions for four points' x and y). A block, not
    /// the scan: a stack copy of all `N` points, zeroed first, cost 12 k instructions a match at
    /// 360 beams in a 1440-beam matcher, and 11.5 KB of stack. The `M` or so centres at each end
    /// go through [`Self::fit_near_ends`].
    #[inline(always)]
    fn fit_all<const M: usize>(&mut self, limits: &FitLimits) {
        const MOST: usize = FIT_BLOCK + 2 * DENSE_LINE_NEIGHBOURS;
        let (mut xs, mut ys) = ([0.0f32; MOST], [0.0f32; MOST]);
        let groups = self.len.saturating_sub(2 * M) / 4;
        let inner = M..M + 4 * groups;
        for block in inner.clone().step_by(FIT_BLOCK) {
            let centres = (inner.end - block).min(FIT_BLOCK);
            let points = &self.points[block - M..block + centres + M];
            for ((x, y), p) in xs.iter_mut().zip(&mut ys).zip(points) {
                (*x, *y) = (p.x, p.y);
            }
            for g in (0..centres).step_by(4) {
                let window = g..g + 2 * M + 4;
                let fits = fit4::<M>(&xs[window.clone()], &ys[window], None, limits);
                let i = block + g;
                self.lines[i..i + 4].copy_from_slice(&LineFit::lines(&fits));
            }
        }
        self.fit_near_ends::<M>(0..M.min(self.len), limits);
        self.fit_near_ends::<M>(inner.end..self.len, limits);
    }

    /// The fits of `centres`, four at a time from a copy of their neighbours.
    #[inline(never)]
    fn fit_near_ends<const M: usize>(&mut self, centres: Range<usize>, limits: &FitLimits) {
        for i in centres.clone().step_by(4) {
            let fits = self.fit_gathered::<M>(i, limits);
            for (c, fit) in (i..centres.end).zip(LineFit::lines(&fits)) {
                self.lines[c] = fit;
            }
        }
    }

    /// [`fit4`] of the centres `i..i + 4` (those past the scan's end fitted to no purpose) from
    /// a gathered copy of their neighbours, each lane capped at the neighbours it may take on
    /// each side: at most `M`, never past the end of a scan that is not a full circle, and on a
    /// full circle never so many that the two sides wrap onto each other (only possible on a
    /// ring of fewer than `2 * M + 1` points, far too few to match).
    fn fit_gathered<const M: usize>(&self, i: usize, limits: &FitLimits) -> Fits {
        const MOST: usize = 2 * DENSE_LINE_NEIGHBOURS + 4;
        let (mut xs, mut ys) = ([0.0f32; MOST], [0.0f32; MOST]);
        // Indices taken round the ring: outside a scan that is not a full circle, the points
        // from its other end are never taken (the caps say so), just finite.
        let mut k = (i as isize - M as isize).rem_euclid(self.len as isize) as usize;
        for (x, y) in xs.iter_mut().zip(&mut ys).take(2 * M + 4) {
            (*x, *y) = (self.points[k].x, self.points[k].y);
            k = if k + 1 == self.len { 0 } else { k + 1 };
        }
        let cap = |side: fn(usize, usize) -> usize| {
            f32x4::from(core::array::from_fn::<f32, 4, _>(|l| {
                let c = i + l;
                let room = if self.full_circle {
                    self.len.saturating_sub(1) / 2
                } else if c < self.len {
                    side(c, self.len)
                } else {
                    0
                };
                room.min(M) as f32
            }))
        };
        // Round a ring of 2 * M + 1 points or more, every lane may take M a side.
        let capped = !self.full_circle || self.len < 2 * M + 1;
        let caps = capped.then(|| (cap(|c, _| c), cap(|c, len| len - 1 - c)));
        fit4::<M>(&xs, &ys, caps, limits)
    }

    /// Whether the scan's beams are closer than [`DENSE_BEAM_STEP_RAD`]. Density is the
    /// sensor's beam step, the least step between consecutive valid beams: the mean over valid
    /// points reads a short-range lidar's many no-return beams as sparseness (the URG-04LX's
    /// 0.36 degrees averaged 0.6 in the simulator's office).
    /// Four steps at a time: one at a time, it was 10 instructions a beam, as many as a
    /// 360-beam scan's line fits spend on three points.
    fn is_dense(&self) -> bool {
        let bearings = &self.bearings[..self.len];
        let steps = self.len.saturating_sub(1);
        let (inf, zero) = (f32x4::splat(f32::INFINITY), f32x4::ZERO);
        let mut least = inf;
        for j in (0..steps - steps % 4).step_by(4) {
            let d = lane(bearings, j + 1) - lane(bearings, j);
            least = least.fast_min(d.cmp_gt(zero).blend(d, inf));
        }
        let step = bearings[steps - steps % 4..]
            .windows(2)
            .map(|b| b[1] - b[0])
            .filter(|&d| d > 0.0)
            .chain(least.to_array())
            .fold(f32::INFINITY, f32::min);
        step < DENSE_BEAM_STEP_RAD
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::matching::prepared::tests::wall_scan;
    use crate::scan::{Beam, Scan};

    #[test]
    fn wall_points_get_the_wall_normal() {
        let mut p: PreparedScan<128> = PreparedScan::default();
        p.load(&wall_scan()).unwrap();
        p.fit_lines(0.5, 0.05, 0.1);
        for i in 0..p.len() {
            let n = p
                .line(i)
                .normal()
                .unwrap_or_else(|| panic!("point {i} has no line"));
            assert!(n.x.abs() > 0.999, "point {i}: {n:?}");
        }
    }

    /// The fit of point `i` by its definition, one point at a time with scalar arithmetic: each
    /// side's reach by walking outwards (capped as [`PreparedScan::fit_gathered`] says), the
    /// moments of the points in reach relative to `p(i)` summed from scratch (the side
    /// below, then the side above), the covariance's eigen decomposition and the flatness test.
    /// Returns the points taken and the normal when it is a line.
    fn fit_by_definition<const N: usize>(
        p: &PreparedScan<N>,
        i: usize,
        most: usize,
        lim: &FitLimits,
    ) -> (usize, Option<Vec2>) {
        let len = p.len();
        let at =
            |k: isize| p.points[(i as isize + k).rem_euclid(len as isize) as usize] - p.points[i];
        let reach = |step: isize| {
            let cap = if p.full_circle {
                (len - 1) / 2
            } else if step < 0 {
                i
            } else {
                len - 1 - i
            };
            let mut taken = 0;
            for k in 1..=cap.min(most) as isize {
                let d2 = at(step * k).norm_squared();
                if d2 > lim.max2 {
                    break;
                }
                taken += 1;
                if d2 >= lim.extent2 && taken >= 2 {
                    break;
                }
            }
            taken
        };
        let (below, above) = (reach(-1), reach(1));
        let count = 1 + below + above;
        let (mut n, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (1.0f32, 0.0, 0.0, 0.0, 0.0, 0.0);
        let below = (1..=below as isize).map(|k| -k);
        for d in below.chain(1..=above as isize).map(at) {
            n += 1.0;
            sx += d.x;
            sy += d.y;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
        if n < 3.0 {
            return (count, None);
        }
        let inv_n = 1.0 / n;
        let (mx, my) = (sx * inv_n, sy * inv_n);
        let (cxx, cxy, cyy) = (
            sxx * inv_n - mx * mx,
            sxy * inv_n - mx * my,
            syy * inv_n - my * my,
        );
        let (hi, lo, normal) = super::super::linalg::sym2_eigen(cxx, cxy, cyy);
        (
            count,
            (hi > 0.0 && lo <= lim.max_flatness * hi).then_some(normal),
        )
    }

    proptest::proptest! {
        /// The four-lane fits must be the fits by definition, bit for bit: the same line or no
        /// line at every point and the same quantised normal (the sums are added in the
        /// definition's order, so nothing rounds differently), on rings and cut scans of walls
        /// at different ranges (so walks stop at gaps and at the extent), sparse (8 neighbours
        /// a side) and dense (16), long and too short for any group of four away from the ends.
        #[test]
        fn lanewise_fits_equal_fits_by_definition(
            walls in proptest::collection::vec((0.3f32..8.0, 3usize..80), 1..10),
            noise in proptest::collection::vec(-0.02f32..0.02, 360),
            beams in proptest::prop_oneof![5usize..40, 200usize..=360],
            dense in proptest::bool::ANY,
        ) {
            // 1 degree round (a ring at 360 beams), or 0.3 degree (dense, never a ring).
            let step = if dense { 0.3f32 } else { 1.0 };
            let mut s: Scan<360> = Scan::new(0.0);
            let mut wall = walls.iter().flat_map(|&(r, n)| core::iter::repeat_n(r, n)).cycle();
            for (i, e) in noise.iter().take(beams).enumerate() {
                let a = (-180.0f32 + step * i as f32).to_radians();
                s.push(Beam::new(a, wall.next().unwrap() + e)).unwrap();
            }
            let mut p: PreparedScan<360> = PreparedScan::default();
            p.load(&s).unwrap();
            proptest::prop_assert_eq!(p.is_dense(), dense);
            let (max_neighbour, flatness, extent) = (0.3, 0.05, 0.1);
            p.fit_lines(max_neighbour, flatness, extent);
            let lim = FitLimits { max2: max_neighbour * max_neighbour, extent2: extent * extent, max_flatness: flatness };
            let most = if dense { DENSE_LINE_NEIGHBOURS } else { LINE_NEIGHBOURS };
            for i in 0..p.len() {
                let (_, want) = fit_by_definition(&p, i, most, &lim);
                // Quantised as the lanes do: half away from zero, then truncated.
                let q = |v: f32| (v * LineFit::SCALE + 0.5f32.copysign(v)) as i16;
                let want = want.map_or(LineFit::default(), |n| LineFit { nx: q(n.x), ny: q(n.y) });
                proptest::prop_assert_eq!(p.line(i), want, "point {} of {}", i, p.len());
            }
        }
    }

    #[test]
    fn a_ring_too_small_for_the_window_never_counts_a_point_twice() {
        // Nine beams round a circle: each side may take at most four neighbours, so the two
        // sides of a fit never reach the same point from both ends of the ring.
        let mut s: Scan<16> = Scan::new(0.0);
        for i in 0..9 {
            s.push(Beam::new((-180.0f32 + 40.0 * i as f32).to_radians(), 0.1))
                .unwrap();
        }
        let mut p: PreparedScan<16> = PreparedScan::default();
        p.load(&s).unwrap();
        assert!(p.full_circle);
        let lim = FitLimits {
            max2: 1.0,
            extent2: 1.0,
            max_flatness: 0.05,
        };
        for i in (0..p.len()).step_by(4) {
            let counts = p.fit_gathered::<LINE_NEIGHBOURS>(i, &lim).count.to_array();
            for (c, &count) in (i..p.len()).zip(&counts) {
                assert_eq!(count, 9.0, "point {c}");
                assert_eq!(fit_by_definition(&p, c, LINE_NEIGHBOURS, &lim).0, 9);
            }
        }
        p.fit_lines(1.0, 0.05, 1.0);
    }
}
