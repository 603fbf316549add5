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
use super::run::Run;
use super::sweep::Sweep;
use crate::geom::Vec2;
use crate::scan::Scan;
use libm::{atan2f, sqrtf};

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
    seam: Option<Gap>,
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
            seam: None,
            len: 0,
            truncated: false,
            sweep_start: 0,
            beams: 0,
        }
    }
}

/// Most hits past a corner handed from the old wall to the new one.
const MAX_HANDED_BACK: usize = 3;

impl<const S: usize> WallSegments<S> {
    /// Segments in sweep order (counter-clockwise from `rule_start_rad`).
    pub fn segments(&self) -> &[WallSegment] {
        &self.segments[..self.len]
    }

    /// Gaps between consecutive segments; `gaps()[k]` lies between segments `k` and `k + 1`.
    pub fn gaps(&self) -> &[Gap] {
        &self.gaps[..self.len.saturating_sub(1)]
    }

    /// The gap across the start of the sweep (behind on the right by default), between the last
    /// segment and the first, when the scan is a full turn. The heading rules do not use it
    /// (their chain starts there); the field closes it when it is narrow.
    pub fn seam_gap(&self) -> Option<&Gap> {
        self.seam.as_ref()
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
        self.extract_sweep(&Sweep::new(scan, cfg.rule_start_rad), cfg);
    }

    /// [`Self::extract`] over a sweep already laid out.
    pub(super) fn extract_sweep<const N: usize>(&mut self, sweep: &Sweep<N>, cfg: &GuidanceConfig) {
        self.len = 0;
        self.truncated = false;
        self.beams = sweep.len();
        self.sweep_start = sweep.beam_index(0);
        let mut run = Run::default();
        for pos in 0..sweep.len() {
            let Some(p) = sweep.hit(pos) else {
                self.close(&mut run, sweep, cfg);
                continue;
            };
            if run.n == 0 {
                run.push(p, pos);
                continue;
            }
            let step = sweep.rel_rad(pos) - sweep.rel_rad(run.last_pos);
            let step_ok = step > 0.0 && step <= cfg.max_beam_step_rad;
            let off_line = run.off_line(p, cfg);
            // A wall seen at a grazing angle has hits far apart but on one line, with no beam
            // passing between them: an established line bridges the spacing.
            let too_far = !run.established(cfg) && (p - run.last).norm() > cfg.max_point_spacing_m;
            if step_ok && off_line && self.hand_over_corner(&mut run, sweep, cfg) {
                run.push(p, pos);
                continue;
            }
            if !step_ok || off_line || too_far {
                self.close(&mut run, sweep, cfg);
            }
            run.push(p, pos);
        }
        self.close(&mut run, sweep, cfg);
        let n = self.len.saturating_sub(1);
        let segments = &self.segments[..self.len];
        self.seam = measure_gaps(segments, &mut self.gaps[..n], sweep, cfg.max_beam_step_rad);
    }

    /// The hits just past a corner can lie within tolerance of the old wall; they are handed
    /// to the new wall while they sit clearly off the old one without them. On a hand-over the
    /// old wall is closed and `run` holds the handed hits; returns whether that happened.
    fn hand_over_corner<const N: usize>(
        &mut self,
        run: &mut Run,
        sweep: &Sweep<N>,
        cfg: &GuidanceConfig,
    ) -> bool {
        let end = run.last_pos;
        let mut kept = *run;
        while end - kept.last_pos < MAX_HANDED_BACK && kept.n >= 3 {
            match kept.split_last(sweep.point(kept.last_pos - 1)) {
                (before, Some(q)) if before.is_outlier(q, cfg) => kept = before,
                _ => break,
            }
        }
        if kept.last_pos == end {
            return false;
        }
        let first_new = kept.last_pos + 1;
        self.close(&mut kept, sweep, cfg);
        *run = Run::default();
        for k in first_new..=end {
            run.push(sweep.point(k), k);
        }
        true
    }

    /// Ends the running fit, keeping it as a segment if it is long and populated enough.
    fn close<const N: usize>(&mut self, run: &mut Run, sweep: &Sweep<N>, cfg: &GuidanceConfig) {
        let mut done = core::mem::take(run);
        if done.n == 0 {
            return;
        }
        self.extend_backward(&mut done, sweep, cfg);
        if done.n >= 4 {
            done.trim_front(sweep.point(done.first_pos + 1), cfg);
        }
        let Some(seg) = segment(&done, sweep) else {
            return;
        };
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

    /// A run starts where its hits come close enough together; the hits before that, far apart
    /// on a wall seen at a grazing angle, join it when they lie on its line, so the wall's
    /// far end is not mistaken for clutter narrowing the opening beyond it.
    fn extend_backward<const N: usize>(
        &self,
        run: &mut Run,
        sweep: &Sweep<N>,
        cfg: &GuidanceConfig,
    ) {
        if !run.established(cfg) {
            return;
        }
        let floor = self.segments().last().map_or(0, |s| s.last_pos + 1);
        while run.first_pos > floor {
            let pos = run.first_pos - 1;
            let step = sweep.rel_rad(run.first_pos) - sweep.rel_rad(pos);
            match sweep.hit(pos) {
                Some(p) if step > 0.0 && step <= cfg.max_beam_step_rad && !run.off_line(p, cfg) => {
                    run.prepend(p, pos)
                }
                _ => break,
            }
        }
    }
}

/// The segment of a run: its line in polar form, its ends projected on it, and the fit
/// quality from the hits themselves (the running sums lose the few millimetres of residual to
/// rounding on walls many metres long).
fn segment<const N: usize>(run: &Run, sweep: &Sweep<N>) -> Option<WallSegment> {
    let l = run.line()?;
    let mut normal = l.normal;
    let mut rho = l.centroid.dot(normal);
    if rho < 0.0 {
        normal = normal * -1.0;
        rho = -rho;
    }
    let project = |p: Vec2| p - normal * (p.dot(normal) - rho);
    let squares: f32 = (run.first_pos..=run.last_pos)
        .map(|pos| {
            let d = sweep.point(pos).dot(normal) - rho;
            d * d
        })
        .sum();
    Some(WallSegment {
        start_m: project(run.first),
        end_m: project(run.last),
        normal_rad: atan2f(normal.y, normal.x),
        distance_m: rho,
        rms_residual_m: sqrtf(squares / run.n as f32),
        points: run.n,
        first_pos: run.first_pos,
        last_pos: run.last_pos,
    })
}
