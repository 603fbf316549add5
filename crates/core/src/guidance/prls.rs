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
use super::gaps::measure_gaps;
pub use super::gaps::Gap;
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
                self.close(&mut run, beams, cfg);
                prev = None;
                continue;
            }
            let p = beam.point();
            let rel = relative_angle(beam.angle_rad, cfg.rule_start_rad);
            let step_ok = prev.is_some_and(|(_, prev_rel)| {
                let step = rel - prev_rel;
                step > 0.0 && step <= cfg.max_beam_step_rad
            });
            let far_from_prev = prev.is_some_and(|(q, _)| (p - q).norm() > cfg.max_point_spacing_m);
            // A wall seen at a grazing angle has hits far apart but on one line, with no beam
            // passing between them: an established line bridges the spacing.
            let breaks = if prev.is_none() {
                false
            } else if !step_ok {
                true
            } else if run.established(cfg) {
                run.off_line(p, cfg)
            } else {
                far_from_prev || run.off_line(p, cfg)
            };
            if breaks && step_ok && run.off_line(p, cfg) {
                // The hits just past a corner can lie within tolerance of the old wall; they
                // are handed to the new wall while they sit clearly off the old one without them.
                let mut handed = 0;
                while handed < MAX_HANDED_BACK && run.n >= 3 {
                    let previous = self.hit(beams, run.last_pos - 1);
                    match run.split_last(previous) {
                        (before, Some(q)) if before.is_outlier(q, cfg) => {
                            run = before;
                            handed += 1;
                        }
                        _ => break,
                    }
                }
                if handed > 0 {
                    let first_new = run.last_pos + 1;
                    self.close(&mut run, beams, cfg);
                    for k in first_new..pos {
                        run.push(self.hit(beams, k), k);
                    }
                    run.push(p, pos);
                    prev = Some((p, rel));
                    continue;
                }
            }
            if breaks {
                self.close(&mut run, beams, cfg);
            }
            run.push(p, pos);
            prev = Some((p, rel));
        }
        self.close(&mut run, beams, cfg);
        self.measure_gaps(scan);
    }

    /// Ends the running fit, keeping it as a segment if it is long and populated enough.
    fn close(&mut self, run: &mut Run, beams: &[Beam], cfg: &GuidanceConfig) {
        let mut done = core::mem::take(run);
        if done.n == 0 {
            return;
        }
        self.extend_backward(&mut done, beams, cfg);
        let hit = |pos: usize| self.hit(beams, pos);
        if done.n >= 4 {
            done.trim_front(hit(done.first_pos + 1), cfg);
        }
        let Some(mut seg) = done.segment() else {
            return;
        };
        // The fit quality from the hits themselves: the running sums lose the few millimetres
        // of residual to rounding on segments many metres long.
        let normal = Vec2::new(cosf(seg.normal_rad), sinf(seg.normal_rad));
        let squares: f32 = (seg.first_pos..=seg.last_pos)
            .map(|pos| {
                let d = hit(pos).dot(normal) - seg.distance_m;
                d * d
            })
            .sum();
        seg.rms_residual_m = sqrtf(squares / seg.points as f32);
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

    /// The hit at sweep position `pos` (only called for positions inside a run, all usable).
    fn hit(&self, beams: &[Beam], pos: usize) -> Vec2 {
        beams[self.beam_index(pos)].point()
    }

    /// A run starts where its hits come close enough together; the hits before that, far apart
    /// on a wall seen at a grazing angle, join it when they lie on its line, so the wall's
    /// far end is not mistaken for clutter narrowing the opening beyond it.
    fn extend_backward(&self, run: &mut Run, beams: &[Beam], cfg: &GuidanceConfig) {
        if !run.established(cfg) {
            return;
        }
        let floor = self.segments().last().map_or(0, |s| s.last_pos + 1);
        let mut next_rel = relative_angle(
            beams[self.beam_index(run.first_pos)].angle_rad,
            cfg.rule_start_rad,
        );
        while run.first_pos > floor {
            let pos = run.first_pos - 1;
            let b = &beams[self.beam_index(pos)];
            let rel = relative_angle(b.angle_rad, cfg.rule_start_rad);
            let step = next_rel - rel;
            if !usable(b)
                || step <= 0.0
                || step > cfg.max_beam_step_rad
                || run.off_line(b.point(), cfg)
            {
                break;
            }
            run.prepend(b.point(), pos);
            next_rel = rel;
        }
    }

    fn measure_gaps<const N: usize>(&mut self, scan: &Scan<N>) {
        let beams = scan.beams();
        let (start, len) = (self.sweep_start, self.beams);
        let hit = |pos: usize| {
            let b = &beams[(start + pos) % len];
            usable(b).then(|| b.point())
        };
        let n = self.len.saturating_sub(1);
        measure_gaps(&self.segments[..self.len], &mut self.gaps[..n], len, hit);
    }
}

/// Most hits past a corner handed from the old wall to the new one.
const MAX_HANDED_BACK: usize = 3;

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
    first: Vec2,
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

/// A total least squares line: centroid and unit normal.
struct Line {
    centroid: Vec2,
    normal: Vec2,
}

impl Run {
    fn push(&mut self, p: Vec2, pos: usize) {
        if self.n == 0 {
            self.origin = p;
            self.first = p;
            self.first_pos = pos;
        }
        self.add(p, 1.0);
        self.last = p;
        self.last_pos = pos;
    }

    /// Drops the first hit when it is an outlier to the line of the others (the last hit of the
    /// wall before a corner, taken before the line could judge it); `second` is the next hit.
    /// Runs of four hits or more only.
    fn trim_front(&mut self, second: Vec2, cfg: &GuidanceConfig) {
        let mut rest = *self;
        rest.add(self.first, -1.0);
        if rest.is_outlier(self.first, cfg) {
            rest.first = second;
            rest.first_pos = self.first_pos + 1;
            *self = rest;
        }
    }

    /// Adds a hit before the first one.
    fn prepend(&mut self, p: Vec2, pos: usize) {
        self.add(p, 1.0);
        self.first = p;
        self.first_pos = pos;
    }

    /// Adds (`sign` 1) or removes (`sign` -1) one hit's share of the sums: the recursion.
    fn add(&mut self, p: Vec2, sign: f32) {
        let d = p - self.origin;
        if sign > 0.0 {
            self.n += 1;
        } else {
            self.n -= 1;
        }
        self.sx += sign * d.x;
        self.sy += sign * d.y;
        self.sxx += sign * d.x * d.x;
        self.sxy += sign * d.x * d.y;
        self.syy += sign * d.y * d.y;
    }

    /// The run without its last hit, and that hit (none for runs of fewer than three hits,
    /// whose remainder would not be a line); `previous` is the hit before the last.
    fn split_last(&self, previous: Vec2) -> (Run, Option<Vec2>) {
        if self.n < 3 {
            return (*self, None);
        }
        let mut before = *self;
        before.add(self.last, -1.0);
        before.last = previous;
        before.last_pos = self.last_pos - 1;
        (before, Some(self.last))
    }

    /// True once the run is long enough for its line to judge new hits: a line through a few
    /// close, noisy hits points anywhere.
    fn established(&self, cfg: &GuidanceConfig) -> bool {
        let base = cfg.min_segment_length_m.max(4.0 * cfg.line_tolerance_m);
        (self.last - self.first).norm() >= base
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
        // direction of least spread.
        let dir = 0.5 * atan2f(2.0 * cxy, cxx - cyy);
        Some(Line {
            centroid: self.origin + Vec2::new(mx, my),
            normal: Vec2::new(-sinf(dir), cosf(dir)),
        })
    }

    /// True when `p` lies farther from the line fitted so far than the tolerance.
    fn off_line(&self, p: Vec2, cfg: &GuidanceConfig) -> bool {
        self.off_line_by(p, cfg.line_tolerance_m)
    }

    /// True when `p` sits off the line by more than three times the run's own scatter (at
    /// least a tenth of the tolerance): a hit of the next wall that the tolerance let in.
    fn is_outlier(&self, p: Vec2, cfg: &GuidanceConfig) -> bool {
        let Some(scatter) = self.scatter_m() else {
            return false;
        };
        self.off_line_by(p, (3.0 * scatter).max(0.1 * cfg.line_tolerance_m))
    }

    /// RMS distance of the run's hits from its line, from the running sums, m.
    fn scatter_m(&self) -> Option<f32> {
        if self.n < 3 {
            return None;
        }
        let n = self.n as f32;
        let (mx, my) = (self.sx / n, self.sy / n);
        let cxx = self.sxx / n - mx * mx;
        let cyy = self.syy / n - my * my;
        let cxy = self.sxy / n - mx * my;
        let half = 0.5 * (cxx - cyy);
        let least = 0.5 * (cxx + cyy) - sqrtf(half * half + cxy * cxy);
        Some(sqrtf(least.max(0.0)))
    }

    fn off_line_by(&self, p: Vec2, tolerance_m: f32) -> bool {
        self.line()
            .is_some_and(|l| (p - l.centroid).dot(l.normal).abs() > tolerance_m)
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
            start_m: project(self.first),
            end_m: project(self.last),
            normal_rad: atan2f(normal.y, normal.x),
            distance_m: rho,
            rms_residual_m: 0.0,
            points: self.n,
            first_pos: self.first_pos,
            last_pos: self.last_pos,
        })
    }
}
