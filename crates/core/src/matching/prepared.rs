//! A scan turned into what matching needs: Cartesian points of the valid beams in angular
//! order, their bearings, and (for a reference) a local line normal per point.
//!
//! Bearings let a query point be projected into the reference's angular order, so a
//! correspondence costs a few comparisons in a window instead of a search over the whole scan
//! (O(N·w), never O(N²)).

use super::fast_math::{atan2_approx, sin_cos, sin_cos_x4};
use super::fit_lanes::{fit4, lane, FitLimits, Fits};
use crate::geom::Vec2;
use crate::scan::{Beam, Scan};
use core::f32::consts::TAU;
use core::ops::Range;
use wide::{f32x4, CmpGt};

/// A point's local line, fitted to its angular neighbours, or none (a corner, clutter, a sparse
/// far wall). Stored in 4 bytes (the unit normal as fixed-point i16 pairs, ample for a
/// direction) because a reference holds one per beam and the whole matcher must fit in 16 KB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineFit {
    nx: i16,
    ny: i16,
}

impl LineFit {
    const SCALE: f32 = i16::MAX as f32;

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

    /// The unit normal, when the neighbourhood is a line.
    pub fn normal(&self) -> Option<Vec2> {
        // Every association pass reads one per point: multiply, a division is far slower.
        const UNSCALE: f32 = 1.0 / LineFit::SCALE;
        (*self != Self::default())
            .then(|| Vec2::new(self.nx as f32 * UNSCALE, self.ny as f32 * UNSCALE))
    }
}

/// Why a scan cannot be used for matching.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrepareError {
    /// Beam angles must increase through the revolution (Plumbline's scan convention).
    BeamsNotInAngularOrder { beam: usize },
}

#[derive(Clone, Debug)]
pub struct PreparedScan<const N: usize> {
    points: [Vec2; N],
    /// Beam angle of each point, unwrapped so that it increases from `bearings[0]`.
    bearings: [f32; N],
    lines: [LineFit; N],
    len: usize,
    /// The beams go all the way round, so windows wrap from the last point to the first.
    full_circle: bool,
    /// Two mean beam steps: how far outside the first and last beam a query still projects.
    margin: f32,
    has_lines: bool,
}

impl<const N: usize> Default for PreparedScan<N> {
    fn default() -> Self {
        Self {
            points: [Vec2::ZERO; N],
            bearings: [0.0; N],
            lines: [LineFit::default(); N],
            len: 0,
            full_circle: false,
            margin: 0.0,
            has_lines: false,
        }
    }
}

/// Most neighbours on each side a point's line fit takes (the fit normally stops earlier, at
/// its spatial extent). Capping at 4 where beams are 1 degree apart was tried: faster and better
/// on Intel (near error 2.3 -> 1.5 cm), but the normals got noisier on 360-beam scans with 2 cm
/// noise (local-map drift test 1.4 -> 2.0 cm).
const LINE_NEIGHBOURS: usize = 8;

/// On scans denser than [`DENSE_BEAM_STEP_RAD`], 8 neighbours were too few: at the URG-04LX's
/// 0.36 degrees they span 5 cm at a metre, under the extent, and with its 1 % range noise most
/// such fits failed the flatness test (a third of the points kept, every match in the recovery
/// search: median 15.6 ms a match in the simulator's room, 53 us with 16). 12 was not enough
/// there (12.5 ms). Sparser scans keep 8: more made the matcher surer of itself than the local
/// map's weighting was tuned for (the synthetic laps' drift 1.4 -> 2.4 cm at 1 degree).
const DENSE_LINE_NEIGHBOURS: usize = 16;

/// Centres whose line fits share one copy of their points (a multiple of 4, the lanes): the
/// copy's `2 * M` points beyond the block's centres are copied again by the next block.
const FIT_BLOCK: usize = 64;

/// Beams closer than this (0.4 degree) make a scan dense: the URG-04LX (0.36), the UTM-30LX
/// (0.25); the 0.5- and 1-degree SICK logs and the XV-11 are not.
const DENSE_BEAM_STEP_RAD: f32 = 0.4 * core::f32::consts::PI / 180.0;

impl<const N: usize> PreparedScan<N> {
    /// Fills from a scan: valid beams only, bearings unwrapped. Lines are fitted separately by
    /// [`Self::fit_lines`] because only a reference needs them.
    pub fn load(&mut self, scan: &Scan<N>) -> Result<(), PrepareError> {
        self.has_lines = false;
        let len = points_of_valid_beams(scan.beams(), &mut self.points, &mut self.bearings);
        self.len = len;
        // The vectorised check says whether; the scalar one, only on a refused scan, says where.
        if !self.in_angular_order() {
            if let Some(beam) = first_out_of_order(scan.beams()) {
                self.len = 0;
                return Err(PrepareError::BeamsNotInAngularOrder { beam });
            }
        }
        let span = if self.len > 1 {
            self.bearings[self.len - 1] - self.bearings[0]
        } else {
            0.0
        };
        // Within 3 beam steps of a full turn: treat as a closed ring.
        self.full_circle = span + 3.0 * self.mean_step() >= TAU;
        self.margin = 2.0 * self.mean_step();
        Ok(())
    }

    /// Whether the kept bearings increase (ties allowed) through at most a turn, measured from
    /// the first as [`first_out_of_order`] measures them. Without early exits, so it vectorises.
    fn in_angular_order(&self) -> bool {
        let b = &self.bearings[..self.len];
        let Some((&a0, _)) = b.split_first() else {
            return true;
        };
        let increasing = b
            .windows(2)
            .fold(true, |ok, w| ok & (w[1] - a0 >= w[0] - a0));
        increasing & (b[b.len() - 1] - a0 <= TAU + 1e-3)
    }

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

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn points(&self) -> &[Vec2] {
        &self.points[..self.len]
    }

    pub fn point(&self, i: usize) -> Vec2 {
        self.points[i]
    }

    pub fn line(&self, i: usize) -> LineFit {
        self.lines[i]
    }

    pub fn has_lines(&self) -> bool {
        self.has_lines
    }

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
        // a jump (a gap in the scan, an occlusion edge) falls back to bisection.
        let mut k = hint.min(self.len);
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

    fn mean_step(&self) -> f32 {
        if self.len > 1 {
            (self.bearings[self.len - 1] - self.bearings[0]) / (self.len - 1) as f32
        } else {
            0.0
        }
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

/// Writes the valid beams' points and angles to the front of `points` and `bearings` and
/// returns how many there are, four beams at a time: finiteness tests, sines and cosines
/// ([`sin_cos_x4`], whose lanes give the scalar [`sin_cos`]'s bits) in lanes; four valid beams,
/// the usual case, are stored at once, and otherwise each beam is written to the next free
/// slot, which only a valid beam keeps. (Validating with a branch per beam, then turning
/// ranges into points in a loop of their own, took 49 instructions a beam.) `points` and
/// `bearings` must be at least as long as `beams`.
fn points_of_valid_beams(beams: &[Beam], points: &mut [Vec2], bearings: &mut [f32]) -> usize {
    let mut len = 0;
    let mut quads = beams.chunks_exact(4);
    for q in &mut quads {
        let range = f32x4::from([q[0].range_m, q[1].range_m, q[2].range_m, q[3].range_m]);
        let angle = [
            q[0].angle_rad,
            q[1].angle_rad,
            q[2].angle_rad,
            q[3].angle_rad,
        ];
        let finite = (range.is_finite() & f32x4::from(angle).is_finite()).move_mask();
        let flags = q
            .iter()
            .enumerate()
            .fold(0, |f, (i, b)| f | i32::from(b.valid) << i);
        let (sin, cos) = sin_cos_x4(f32x4::from(angle));
        let (x, y) = ((range * cos).to_array(), (range * sin).to_array());
        let keep = finite & flags;
        // `len` counts the valid beams before these four, so it is at most their first index.
        if keep == 0b1111 {
            let (p, a) = (&mut points[len..len + 4], &mut bearings[len..len + 4]);
            for i in 0..4 {
                p[i] = Vec2::new(x[i], y[i]);
            }
            a.copy_from_slice(&angle);
            len += 4;
        } else {
            for i in 0..4 {
                points[len] = Vec2::new(x[i], y[i]);
                bearings[len] = angle[i];
                len += (keep >> i & 1) as usize;
            }
        }
    }
    for beam in quads.remainder() {
        let (sin, cos) = sin_cos(beam.angle_rad);
        points[len] = Vec2::new(beam.range_m * cos, beam.range_m * sin);
        bearings[len] = beam.angle_rad;
        len += usize::from(beam.valid & beam.range_m.is_finite() & beam.angle_rad.is_finite());
    }
    len
}

/// The first valid beam whose bearing from the first valid beam is below its predecessor's or
/// beyond a turn; the slow path of [`PreparedScan::load`], taken only for a scan it refuses.
#[cold]
fn first_out_of_order(beams: &[Beam]) -> Option<usize> {
    let mut first = None;
    let mut prev = f32::NEG_INFINITY;
    for (i, beam) in beams.iter().enumerate() {
        if !(beam.valid && beam.range_m.is_finite() && beam.angle_rad.is_finite()) {
            continue;
        }
        let bearing = beam.angle_rad - *first.get_or_insert(beam.angle_rad);
        if bearing < prev || bearing > TAU + 1e-3 {
            return Some(i);
        }
        prev = bearing;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::Beam;

    fn wall_scan() -> Scan<128> {
        // A wall at x = 2, seen from -60 to +60 degrees.
        let mut s = Scan::new(0.0);
        for i in 0..121 {
            let a = (-60.0f32 + i as f32).to_radians();
            s.push(Beam::new(a, 2.0 / libm::cosf(a))).unwrap();
        }
        s
    }

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

    proptest::proptest! {
        /// The branch-free load refuses exactly the scans the beam-by-beam rule refuses, naming
        /// the same beam, and otherwise keeps exactly the valid beams: on scans with invalid and
        /// non-finite beams, backward steps, ties and spans past a turn.
        #[test]
        fn load_keeps_valid_beams_and_refuses_as_the_scalar_rule_does(
            beams in proptest::collection::vec(
                (0.0f32..0.2, proptest::bool::weighted(0.8), 0u8..40), 0..64
            ),
            start in -4.0f32..4.0,
        ) {
            let mut s: Scan<64> = Scan::new(0.0);
            let mut angle = start;
            for &(step, valid, kind) in &beams {
                // Mostly forward steps (often past a turn in all), now and then a tie, a step
                // back or a non-finite value.
                angle += match kind {
                    0 => 0.0,
                    1 => -step,
                    _ => step,
                };
                let range = if kind == 2 { f32::NAN } else { 1.0 + step };
                let a = if kind == 3 { f32::INFINITY } else { angle };
                let mut b = Beam::new(a, range);
                b.valid &= valid;
                s.push(b).unwrap();
            }
            let mut p: PreparedScan<64> = PreparedScan::default();
            match first_out_of_order(s.beams()) {
                Some(beam) => proptest::prop_assert_eq!(
                    p.load(&s), Err(PrepareError::BeamsNotInAngularOrder { beam })
                ),
                None => {
                    proptest::prop_assert_eq!(p.load(&s), Ok(()));
                    let kept = s.beams().iter().filter(|b| {
                        b.valid && b.range_m.is_finite() && b.angle_rad.is_finite()
                    });
                    proptest::prop_assert_eq!(p.len(), kept.clone().count());
                    for (i, b) in kept.enumerate() {
                        let d = (p.point(i) - b.point()).norm();
                        proptest::prop_assert!(d < 1e-5, "beam {}: {:?} vs {:?}", i, p.point(i), b.point());
                    }
                }
            }
        }
    }

    #[test]
    fn out_of_order_beams_are_refused() {
        let mut s: Scan<4> = Scan::new(0.0);
        s.push(Beam::new(0.5, 1.0)).unwrap();
        s.push(Beam::new(0.1, 1.0)).unwrap();
        let mut p: PreparedScan<4> = PreparedScan::default();
        assert_eq!(
            p.load(&s),
            Err(PrepareError::BeamsNotInAngularOrder { beam: 1 })
        );
    }
}
