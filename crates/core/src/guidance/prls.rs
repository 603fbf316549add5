//! Wall segments from one revolution by polar recursive least squares (seed 002, sec. II.B.1).
//!
//! Hits are taken in angular order, counter-clockwise from the heading rules' start angle (the
//! seed's "beginning of the scan on the right"). Each hit either extends the running line fit,
//! updated recursively from six running sums, or ends it: an invalid beam, a hole in the beam
//! angles, a jump between hits, or a hit farther from the fitted line than the tolerance. Lines
//! are kept in polar (normal) form, `p · (cos α, sin α) = ρ` in the sensor frame, which is how
//! the heading rules use them. The openings between consecutive segments are the gaps, each
//! with the free width across it.
//!
//! Degraded input: an empty scan or one with no valid beam gives no segments and no gaps (the
//! guidance then hovers, see [`super::step`]); more segments than the capacity `S` keeps the
//! first `S` in sweep order and sets [`WallSegments::truncated`].

use super::config::GuidanceConfig;
use crate::geom::Vec2;
use crate::scan::{Beam, Scan};
use core::f32::consts::TAU;
use libm::{atan2f, cosf, sinf, sqrtf};

/// A straight piece of wall, in the sensor frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WallSegment {
    /// The first hit of the segment in sweep order, projected onto the fitted line, m.
    pub start_m: Vec2,
    /// The last hit, projected onto the fitted line, m.
    pub end_m: Vec2,
    /// Direction of the line's normal pointing away from the sensor, rad (`α`).
    pub normal_rad: f32,
    /// Distance from the sensor to the (infinite) line, m (`ρ` ≥ 0).
    pub distance_m: f32,
    /// Root mean square distance of the segment's hits from the line, m: the fit quality.
    pub rms_residual_m: f32,
    /// Number of hits in the fit.
    pub points: usize,
    /// Positions of the first and last hit in sweep order (see [`WallSegments::beam_index`]).
    pub first_pos: usize,
    pub last_pos: usize,
}

impl WallSegment {
    pub fn length_m(&self) -> f32 {
        (self.end_m - self.start_m).norm()
    }

    /// Direction from start to end (counter-clockwise sweep order), rad in the sensor frame.
    /// With the wall on the right this points where a right-hand wall follower flies.
    pub fn direction_rad(&self) -> f32 {
        let d = self.end_m - self.start_m;
        atan2f(d.y, d.x)
    }
}

/// The opening between segment `after` and segment `after + 1`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gap {
    /// Index of the segment before the gap; the one after is `after + 1`.
    pub after: usize,
    /// Last hit of the segment before and first hit of the one after, sensor frame, m.
    pub from_m: Vec2,
    pub to_m: Vec2,
    /// Free width across the gap, m: the shortest distance from either side of the opening
    /// to any hit on the other side of it (so a person standing in a door narrows the door).
    pub width_m: f32,
}

/// Segments and gaps of one revolution, at most `S` segments, stored inline.
#[derive(Clone, Debug)]
pub struct WallSegments<const S: usize> {
    segments: [WallSegment; S],
    gaps: [Gap; S],
    len: usize,
    truncated: bool,
    sweep_start: usize,
    beams: usize,
}

impl<const S: usize> Default for WallSegments<S> {
    fn default() -> Self {
        Self {
            segments: [WallSegment::default(); S],
            gaps: [Gap::default(); S],
            len: 0,
            truncated: false,
            sweep_start: 0,
            beams: 0,
        }
    }
}

impl<const S: usize> WallSegments<S> {
    /// Segments in sweep order (counter-clockwise from `rule_start_rad`).
    pub fn segments(&self) -> &[WallSegment] {
        &self.segments[..self.len]
    }

    /// Gaps between consecutive segments; `gaps()[k]` lies between segments `k` and `k + 1`.
    pub fn gaps(&self) -> &[Gap] {
        &self.gaps[..self.len.saturating_sub(1)]
    }

    /// True when the scan held more segments than `S`: the later ones were dropped.
    pub fn truncated(&self) -> bool {
        self.truncated
    }

    /// Number of beams in the sweep (the scan's length).
    pub fn sweep_len(&self) -> usize {
        self.beams
    }

    /// Index into `scan.beams()` of sweep position `pos` (`pos < sweep_len()`).
    pub fn beam_index(&self, pos: usize) -> usize {
        (self.sweep_start + pos) % self.beams.max(1)
    }

    /// Runs PRLS over `scan` (the configuration must have passed `validate`).
    pub fn extract<const N: usize>(&mut self, scan: &Scan<N>, cfg: &GuidanceConfig) {
        let beams = scan.beams();
        self.len = 0;
        self.truncated = false;
        self.beams = beams.len();
        self.sweep_start = sweep_start(beams, cfg.rule_start_rad);
        let mut run = Run::default();
        let mut prev: Option<(Vec2, f32)> = None;
        for pos in 0..beams.len() {
            let beam = &beams[self.beam_index(pos)];
            if !usable(beam) {
                self.close(&mut run, cfg);
                prev = None;
                continue;
            }
            let p = beam.point();
            let rel = relative_angle(beam.angle_rad, cfg.rule_start_rad);
            let breaks = match prev {
                None => false,
                Some((q, prev_rel)) => {
                    let step = rel - prev_rel;
                    step <= 0.0
                        || step > cfg.max_beam_step_rad
                        || (p - q).norm() > cfg.max_point_spacing_m
                        || run.off_line(p, cfg)
                }
            };
            if breaks {
                self.close(&mut run, cfg);
            }
            run.push(p, pos);
            prev = Some((p, rel));
        }
        self.close(&mut run, cfg);
        self.measure_gaps(scan);
    }

    /// Ends the running fit, keeping it as a segment if it is long and populated enough.
    fn close(&mut self, run: &mut Run, cfg: &GuidanceConfig) {
        let done = core::mem::take(run);
        let Some(seg) = done.segment() else { return };
        if seg.points < usize::from(cfg.min_segment_points)
            || seg.length_m() < cfg.min_segment_length_m
        {
            return;
        }
        match self.segments.get_mut(self.len) {
            Some(slot) => {
                *slot = seg;
                self.len += 1;
            }
            None => self.truncated = true,
        }
    }

    fn measure_gaps<const N: usize>(&mut self, scan: &Scan<N>) {
        let beams = scan.beams();
        let (start, len) = (self.sweep_start, self.beams);
        let hit = |pos: usize| {
            let b = &beams[(start + pos) % len];
            usable(b).then(|| b.point())
        };
        for k in 0..self.len.saturating_sub(1) {
            let (a, b) = (self.segments[k], self.segments[k + 1]);
            let from = hit(a.last_pos).unwrap_or(a.end_m);
            let to = hit(b.first_pos).unwrap_or(b.start_m);
            let nearest = |p: Vec2, range: core::ops::Range<usize>| {
                range
                    .filter_map(hit)
                    .map(|q| (q - p).norm())
                    .fold(f32::INFINITY, f32::min)
            };
            let width = (to - from)
                .norm()
                .min(nearest(from, a.last_pos + 1..len))
                .min(nearest(to, 0..b.first_pos));
            self.gaps[k] = Gap {
                after: k,
                from_m: from,
                to_m: to,
                width_m: width,
            };
        }
    }
}

/// A beam whose hit can be used: flagged valid and with a finite positive range and angle.
pub(crate) fn usable(b: &Beam) -> bool {
    b.valid && b.range_m.is_finite() && b.range_m > 0.0 && b.angle_rad.is_finite()
}

/// Angle counter-clockwise from `start`, in [0, 2π).
pub(crate) fn relative_angle(angle_rad: f32, start_rad: f32) -> f32 {
    let r = libm::fmodf(angle_rad - start_rad, TAU);
    let r = if r < 0.0 { r + TAU } else { r };
    // Rounding can land a tiny negative remainder exactly on 2π.
    if r >= TAU {
        0.0
    } else {
        r
    }
}

/// The beam first counter-clockwise from `start_rad`: where the sweep begins.
fn sweep_start(beams: &[Beam], start_rad: f32) -> usize {
    let mut best = (0, f32::INFINITY);
    for (i, b) in beams.iter().enumerate() {
        let rel = if b.angle_rad.is_finite() {
            relative_angle(b.angle_rad, start_rad)
        } else {
            f32::INFINITY
        };
        if rel < best.1 {
            best = (i, rel);
        }
    }
    best.0
}

/// The running fit: sums of hits relative to the first one (relative sums keep f32 exact
/// enough far from the sensor), updated one hit at a time.
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    origin: Vec2,
    last: Vec2,
    first_pos: usize,
    last_pos: usize,
    n: usize,
    sx: f32,
    sy: f32,
    sxx: f32,
    sxy: f32,
    syy: f32,
}

/// A total least squares line: centroid, unit normal and RMS residual.
struct Line {
    centroid: Vec2,
    normal: Vec2,
    rms_m: f32,
}

impl Run {
    fn push(&mut self, p: Vec2, pos: usize) {
        if self.n == 0 {
            self.origin = p;
            self.first_pos = pos;
        }
        let d = p - self.origin;
        self.n += 1;
        self.sx += d.x;
        self.sy += d.y;
        self.sxx += d.x * d.x;
        self.sxy += d.x * d.y;
        self.syy += d.y * d.y;
        self.last = p;
        self.last_pos = pos;
    }

    fn line(&self) -> Option<Line> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f32;
        let (mx, my) = (self.sx / n, self.sy / n);
        let cxx = self.sxx / n - mx * mx;
        let cyy = self.syy / n - my * my;
        let cxy = self.sxy / n - mx * my;
        // The line runs along the principal axis of the hits' scatter; its normal is the
        // direction of least spread, whose variance is the mean squared residual.
        let dir = 0.5 * atan2f(2.0 * cxy, cxx - cyy);
        let normal = Vec2::new(-sinf(dir), cosf(dir));
        let half = 0.5 * (cxx - cyy);
        let least = 0.5 * (cxx + cyy) - sqrtf(half * half + cxy * cxy);
        Some(Line {
            centroid: self.origin + Vec2::new(mx, my),
            normal,
            rms_m: sqrtf(least.max(0.0)),
        })
    }

    /// True when `p` lies farther from the line fitted so far than the tolerance. Short runs are
    /// not judged: a line through a few close, noisy hits points anywhere.
    fn off_line(&self, p: Vec2, cfg: &GuidanceConfig) -> bool {
        let base = cfg.min_segment_length_m.max(4.0 * cfg.line_tolerance_m);
        if (self.last - self.origin).norm() < base {
            return false;
        }
        self.line()
            .is_some_and(|l| (p - l.centroid).dot(l.normal).abs() > cfg.line_tolerance_m)
    }

    fn segment(&self) -> Option<WallSegment> {
        let l = self.line()?;
        let mut normal = l.normal;
        let mut rho = l.centroid.dot(normal);
        if rho < 0.0 {
            normal = Vec2::new(-normal.x, -normal.y);
            rho = -rho;
        }
        let project = |p: Vec2| p - normal * (p.dot(normal) - rho);
        Some(WallSegment {
            start_m: project(self.origin),
            end_m: project(self.last),
            normal_rad: atan2f(normal.y, normal.x),
            distance_m: rho,
            rms_residual_m: l.rms_m,
            points: self.n,
            first_pos: self.first_pos,
            last_pos: self.last_pos,
        })
    }
}
