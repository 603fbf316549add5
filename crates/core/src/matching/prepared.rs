//! A scan turned into what matching needs: Cartesian points of the valid beams in angular
//! order, their bearings, and (for a reference) a local line normal per point.
//!
//! Bearings let a query point be projected into the reference's angular order, so a
//! correspondence costs a few comparisons in a window instead of a search over the whole scan
//! (O(N·w), never O(N²)).

use super::fast_math::{atan2_approx, sin_cos};
use super::linalg::sym2_eigen;
use crate::geom::Vec2;
use crate::scan::Scan;
use core::f32::consts::TAU;

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
    #[inline(always)]
    fn line(normal: Vec2) -> Self {
        // Round half away from zero by hand: libm's roundf is a call per component. No clamp:
        // the normal is a unit vector, and a component that rounds a hair past 1 still lands on
        // i16::MAX because `as` saturates.
        let q = |v: f32| (v * Self::SCALE + 0.5f32.copysign(v)) as i16;
        LineFit {
            nx: q(normal.x),
            ny: q(normal.y),
        }
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

/// Beams closer than this (0.4 degree) make a scan dense: the URG-04LX (0.36), the UTM-30LX
/// (0.25); the 0.5- and 1-degree SICK logs and the XV-11 are not.
const DENSE_BEAM_STEP_RAD: f32 = 0.4 * core::f32::consts::PI / 180.0;

impl<const N: usize> PreparedScan<N> {
    /// Fills from a scan: valid beams only, bearings unwrapped. Lines are fitted separately by
    /// [`Self::fit_lines`] because only a reference needs them.
    pub fn load(&mut self, scan: &Scan<N>) -> Result<(), PrepareError> {
        self.len = 0;
        self.has_lines = false;
        let mut first = None;
        let mut prev = f32::NEG_INFINITY;
        for (i, beam) in scan.beams().iter().enumerate() {
            if !(beam.valid && beam.range_m.is_finite() && beam.angle_rad.is_finite()) {
                continue;
            }
            let a0 = *first.get_or_insert(beam.angle_rad);
            let bearing = beam.angle_rad - a0;
            if bearing < prev || bearing > TAU + 1e-3 {
                return Err(PrepareError::BeamsNotInAngularOrder { beam: i });
            }
            prev = bearing;
            // The range waits in x for the loop below.
            self.points[self.len] = Vec2::new(beam.range_m, 0.0);
            self.bearings[self.len] = beam.angle_rad;
            self.len += 1;
        }
        // Sines and cosines in a loop of their own, without branches or early exits, so the
        // compiler evaluates the polynomials for several beams at once.
        let valid = self.points[..self.len].iter_mut();
        for (p, &a) in valid.zip(&self.bearings[..self.len]) {
            let (sin, cos) = sin_cos(a);
            *p = Vec2::new(p.x * cos, p.x * sin);
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

    /// Fits a local line to every point from its angular neighbours on each side, walking
    /// outwards until they span `min_extent_m` (or `LINE_NEIGHBOURS` points, 16 on dense scans, or a neighbour
    /// farther than `max_neighbour_m`, a gap). A spatial extent, not a beam count, is what makes
    /// the fit rise above range noise at every beam density; points on clutter or alone get none.
    ///
    /// Consecutive points share most of their neighbours, so the sums of one fit are carried to
    /// the next ([`Neighbourhood`]): only the points at the window's ends are added or removed.
    pub fn fit_lines(&mut self, max_neighbour_m: f32, max_flatness: f32, min_extent_m: f32) {
        let limits = FitLimits {
            max2: max_neighbour_m * max_neighbour_m,
            extent2: min_extent_m * min_extent_m,
            max_flatness,
        };
        // The cap as a constant, so each side's walk is a fixed-length slice the compiler
        // unrolls (as a run-time value it cost 360-beam matches 8 % more instructions).
        if self.is_dense() {
            self.fit_all::<DENSE_LINE_NEIGHBOURS>(&limits);
        } else {
            self.fit_all::<LINE_NEIGHBOURS>(&limits);
        }
        self.has_lines = true;
    }

    /// [`Self::fit_lines`] with at most `M` neighbours a side.
    #[inline(always)]
    fn fit_all<const M: usize>(&mut self, limits: &FitLimits) {
        let mut window = Neighbourhood::default();
        for i in 0..self.len {
            let below = self.reach::<M>(i, -1, limits);
            let above = self.reach::<M>(i, 1, limits);
            window.slide(self, i, i as isize - below, i as isize + above);
            self.lines[i] = window.line(limits);
        }
    }

    /// Whether the scan's beams are closer than [`DENSE_BEAM_STEP_RAD`]. Density is the
    /// sensor's beam step, the least step between consecutive valid beams: the mean over valid
    /// points reads a short-range lidar's many no-return beams as sparseness (the URG-04LX's
    /// 0.36 degrees averaged 0.6 in the simulator's office).
    fn is_dense(&self) -> bool {
        let bearings = &self.bearings[..self.len];
        let step = bearings
            .windows(2)
            .map(|b| b[1] - b[0])
            .filter(|&d| d > 0.0)
            .fold(f32::INFINITY, f32::min);
        step < DENSE_BEAM_STEP_RAD
    }

    /// How many neighbours of point `i` on one side (`step` -1 or 1) its line fit takes: see
    /// [`reach`]. At most `M`, never past the end of a scan that is not a full circle, and on a
    /// full circle never so many that the two sides wrap onto each other (only possible on a
    /// ring of fewer than `2 * M + 1` points, far too few to match).
    #[inline(always)]
    fn reach<const M: usize>(&self, i: usize, step: isize, lim: &FitLimits) -> isize {
        let c = self.points[i];
        // Away from the ends the neighbours are a plain slice.
        if i >= M && i + M < self.len {
            return if step < 0 {
                reach(self.points[i - M..i].iter().rev().copied(), c, lim)
            } else {
                reach(self.points[i + 1..=i + M].iter().copied(), c, lim)
            };
        }
        let cap = if self.full_circle {
            (self.len - 1) / 2
        } else if step < 0 {
            i
        } else {
            self.len - 1 - i
        };
        let side = (1..=cap.min(M) as isize).map(|k| self.at(i as isize + step * k));
        reach(side, c, lim)
    }

    /// The point at unwrapped index `j`: in the scan, or (on a full circle) within a turn of it.
    #[inline(always)]
    fn at(&self, j: isize) -> Vec2 {
        let n = self.len as isize;
        let j = if j < 0 {
            j + n
        } else if j >= n {
            j - n
        } else {
            j
        };
        self.points[j as usize]
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

/// When a neighbourhood counts as a line (squared distances, m²).
struct FitLimits {
    max2: f32,
    extent2: f32,
    max_flatness: f32,
}

/// How many of the neighbours of `c` on one side, nearest first, a line fit takes: up to a gap
/// (a neighbour farther than the limit, left out) or until they span the extent (two at least,
/// so a scan's end points still get a line).
#[inline(always)]
fn reach(side: impl Iterator<Item = Vec2>, c: Vec2, lim: &FitLimits) -> isize {
    let mut taken = 0;
    for p in side {
        let d2 = (p - c).norm_squared();
        if d2 > lim.max2 {
            break;
        }
        taken += 1;
        if d2 >= lim.extent2 && taken >= 2 {
            break;
        }
    }
    taken
}

/// The points `lo..=hi` (indices unwrapped, so on a full circle they may run past either end)
/// summed relative to the point a fit is centred on. Relative sums stay centimetre-scale, so
/// adding and removing points in f32 loses nothing that matters; moving the centre by `d` is a
/// closed-form update of the sums ([`Moments::recentre`]).
struct Neighbourhood {
    lo: isize,
    hi: isize,
    centre: Vec2,
    m: Moments,
}

impl Default for Neighbourhood {
    fn default() -> Self {
        Self {
            lo: 0,
            hi: -1,
            centre: Vec2::ZERO,
            m: Moments::default(),
        }
    }
}

impl Neighbourhood {
    /// Moves to the points `lo..=hi` around point `i`: removes those that left (relative to the
    /// old centre), recentres, then adds those that entered. Ranges that do not overlap start
    /// from zero, so a jump across a gap never subtracts metre-scale sums. Overlapping ranges
    /// share a point within a fit's neighbour distance of both centres, so the shift is short.
    /// Always inlined: with two fit loops (sparse and dense scans) the compiler made it a call,
    /// 6 % more instructions a 360-beam match.
    #[inline(always)]
    fn slide<const N: usize>(&mut self, scan: &PreparedScan<N>, i: usize, lo: isize, hi: isize) {
        let c = scan.points[i];
        if self.lo > self.hi || lo > self.hi || hi < self.lo {
            self.m = Moments::default();
            self.centre = c;
            (self.lo, self.hi) = (lo, lo - 1);
        }
        for j in self.lo..lo {
            self.m.remove(scan.at(j) - self.centre);
        }
        for j in hi + 1..=self.hi {
            self.m.remove(scan.at(j) - self.centre);
        }
        self.m.recentre(c - self.centre);
        self.centre = c;
        for j in lo..self.lo {
            self.m.add(scan.at(j) - c);
        }
        for j in self.hi + 1..=hi {
            self.m.add(scan.at(j) - c);
        }
        (self.lo, self.hi) = (lo, hi);
    }

    /// The line through the centre fitted to the neighbourhood (none with fewer than two
    /// neighbours, or when the spread across the line is more than the flatness limit allows).
    /// Always inlined: as a call, the sums went through memory once per point.
    #[inline(always)]
    fn line(&self, lim: &FitLimits) -> LineFit {
        let m = &self.m;
        if m.n < 3.0 {
            return LineFit::default();
        }
        let inv_n = 1.0 / m.n;
        let (mx, my) = (m.sx * inv_n, m.sy * inv_n);
        let (cxx, cxy, cyy) = (
            m.sxx * inv_n - mx * mx,
            m.sxy * inv_n - mx * my,
            m.syy * inv_n - my * my,
        );
        let (hi, lo, normal) = sym2_eigen(cxx, cxy, cyy);
        if hi > 0.0 && lo <= lim.max_flatness * hi {
            LineFit::line(normal)
        } else {
            LineFit::default()
        }
    }
}

/// Count, first and second moments of points relative to a centre.
#[derive(Default)]
struct Moments {
    n: f32,
    sx: f32,
    sy: f32,
    sxx: f32,
    sxy: f32,
    syy: f32,
}

impl Moments {
    fn add(&mut self, d: Vec2) {
        self.n += 1.0;
        self.sx += d.x;
        self.sy += d.y;
        self.sxx += d.x * d.x;
        self.sxy += d.x * d.y;
        self.syy += d.y * d.y;
    }

    fn remove(&mut self, d: Vec2) {
        self.n -= 1.0;
        self.sx -= d.x;
        self.sy -= d.y;
        self.sxx -= d.x * d.x;
        self.sxy -= d.x * d.y;
        self.syy -= d.y * d.y;
    }

    /// The same points relative to a centre `d` further on: sum (p - d) = S1 - n d and
    /// sum (p - d)(p - d)^T = S2 - S1 d^T - d S1^T + n d d^T.
    fn recentre(&mut self, d: Vec2) {
        let (sx, sy) = (self.sx, self.sy);
        self.sxx += d.x * (self.n * d.x - 2.0 * sx);
        self.sxy += self.n * d.x * d.y - sx * d.y - sy * d.x;
        self.syy += d.y * (self.n * d.y - 2.0 * sy);
        self.sx -= self.n * d.x;
        self.sy -= self.n * d.y;
    }
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

    proptest::proptest! {
        /// Sums carried from point to point (ends added and removed, the centre moved in closed
        /// form) must equal the sums of each fit's neighbourhood taken from scratch: on rings and
        /// cut scans of walls at different ranges, so windows shrink at gaps and start over.
        #[test]
        fn carried_line_sums_equal_sums_from_scratch(
            walls in proptest::collection::vec((0.3f32..8.0, 3usize..80), 1..10),
            noise in proptest::collection::vec(-0.02f32..0.02, 360),
            ring in proptest::bool::ANY,
        ) {
            let beams = if ring { 360 } else { 240 };
            let mut s: Scan<360> = Scan::new(0.0);
            let mut wall = walls.iter().flat_map(|&(r, n)| core::iter::repeat_n(r, n)).cycle();
            for (i, e) in noise.iter().take(beams).enumerate() {
                let a = (-180.0f32 + i as f32).to_radians();
                s.push(Beam::new(a, wall.next().unwrap() + e)).unwrap();
            }
            let mut p: PreparedScan<360> = PreparedScan::default();
            p.load(&s).unwrap();
            let lim = FitLimits { max2: 0.09, extent2: 0.01, max_flatness: 0.05 };
            let mut carried = Neighbourhood::default();
            for i in 0..p.len() {
                const M: usize = LINE_NEIGHBOURS;
                let (lo, hi) = (i as isize - p.reach::<M>(i, -1, &lim), i as isize + p.reach::<M>(i, 1, &lim));
                carried.slide(&p, i, lo, hi);
                let mut fresh = Neighbourhood::default();
                fresh.slide(&p, i, lo, hi);
                let (a, b) = (&carried.m, &fresh.m);
                proptest::prop_assert_eq!(a.n, b.n);
                for (x, y) in [(a.sx, b.sx), (a.sy, b.sy), (a.sxx, b.sxx), (a.sxy, b.sxy), (a.syy, b.syy)] {
                    proptest::prop_assert!((x - y).abs() < 1e-5, "point {}: {} vs {}", i, x, y);
                }
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
        for i in 0..p.len() {
            let sides = (
                p.reach::<LINE_NEIGHBOURS>(i, -1, &lim),
                p.reach::<LINE_NEIGHBOURS>(i, 1, &lim),
            );
            assert_eq!(sides, (4, 4));
        }
        p.fit_lines(1.0, 0.05, 1.0);
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
