//! A scan turned into what matching needs: Cartesian points of the valid beams in angular
//! order, their bearings, and (for a reference) a local line normal per point.
//!
//! Loading lives here. The line fits are in [`super::line_fit`]; the search for where a query
//! falls in the angular order and which point is nearest it, in [`super::nearest`].

use crate::fast_math::{sin_cos, sin_cos_x4};
use crate::geom::Vec2;
use crate::scan::{AngularOrder, Beam, Scan};
use core::f32::consts::TAU;
use wide::f32x4;

/// A point's local line, fitted to its angular neighbours, or none (a corner, clutter, a sparse
/// far wall). Stored in 4 bytes (the unit normal as fixed-point i16 pairs, ample for a
/// direction) because a reference holds one per beam and the whole matcher must fit in 16 KB.
/// The fits fill it ([`super::line_fit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineFit {
    pub(super) nx: i16,
    pub(super) ny: i16,
}

impl LineFit {
    pub(super) const SCALE: f32 = i16::MAX as f32;

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
    pub(super) points: [Vec2; N],
    /// Beam angle of each point, unwrapped so that it increases from `bearings[0]`.
    pub(super) bearings: [f32; N],
    pub(super) lines: [LineFit; N],
    pub(super) len: usize,
    /// The beams go all the way round, so windows wrap from the last point to the first.
    pub(super) full_circle: bool,
    /// Two mean beam steps: how far outside the first and last beam a query still projects.
    pub(super) margin: f32,
    pub(super) has_lines: bool,
    /// The bearings never decrease (as stored, not only as measured from the first), so the
    /// place of a bearing among them is one whatever a search starts from.
    pub(super) sorted: bool,
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
            sorted: false,
        }
    }
}

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
        let b = &self.bearings[..self.len];
        self.sorted = b.windows(2).fold(true, |ok, w| ok & (w[1] >= w[0]));
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

    fn mean_step(&self) -> f32 {
        if self.len > 1 {
            (self.bearings[self.len - 1] - self.bearings[0]) / (self.len - 1) as f32
        } else {
            0.0
        }
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
    let mut order = AngularOrder::default();
    beams.iter().position(|beam| {
        beam.valid
            && beam.range_m.is_finite()
            && beam.angle_rad.is_finite()
            && !order.admits(beam.angle_rad)
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A wall at x = 2, seen from -60 to +60 degrees.
    pub(in crate::matching) fn wall_scan() -> Scan<128> {
        let mut s = Scan::new(0.0);
        for i in 0..121 {
            let a = (-60.0f32 + i as f32).to_radians();
            s.push(Beam::new(a, 2.0 / libm::cosf(a))).unwrap();
        }
        s
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
