//! The running line fit of PRLS: six sums of the hits (relative to the first, which keeps f32
//! exact enough metres from the sensor), updated one hit at a time in either direction, and the
//! total least squares line they define.

use super::config::GuidanceConfig;
use crate::geom::Vec2;
use libm::sqrtf;

#[derive(Clone, Copy, Debug, Default)]
pub struct Run {
    origin: Vec2,
    pub first: Vec2,
    pub last: Vec2,
    pub first_pos: usize,
    pub last_pos: usize,
    pub n: usize,
    sx: f32,
    sy: f32,
    sxx: f32,
    sxy: f32,
    syy: f32,
}

/// A line through `centroid` with unit `normal`.
pub struct Line {
    pub centroid: Vec2,
    pub normal: Vec2,
}

/// Second moments of a run's hits about their centroid.
struct Spread {
    centroid: Vec2,
    xx: f32,
    xy: f32,
    yy: f32,
}

impl Spread {
    /// The smaller eigenvalue: the mean squared distance from the best line.
    fn least(&self) -> f32 {
        let half = 0.5 * (self.xx - self.yy);
        0.5 * (self.xx + self.yy) - sqrtf(half * half + self.xy * self.xy)
    }
}

impl Run {
    /// Appends a hit after the last one.
    pub fn push(&mut self, p: Vec2, pos: usize) {
        if self.n == 0 {
            self.origin = p;
            self.first = p;
            self.first_pos = pos;
        }
        self.add(p, 1.0);
        self.last = p;
        self.last_pos = pos;
    }

    /// Adds a hit before the first one.
    pub fn prepend(&mut self, p: Vec2, pos: usize) {
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
    pub fn split_last(&self, previous: Vec2) -> (Run, Option<Vec2>) {
        if self.n < 3 {
            return (*self, None);
        }
        let mut before = *self;
        before.add(self.last, -1.0);
        before.last = previous;
        before.last_pos = self.last_pos - 1;
        (before, Some(self.last))
    }

    /// Drops the first hit when it is an outlier to the line of the others (the last hit of the
    /// wall before a corner, taken before the line could judge it); `second` is the next hit.
    pub fn trim_front(&mut self, second: Vec2, cfg: &GuidanceConfig) {
        if self.n < 4 {
            return;
        }
        let mut rest = *self;
        rest.add(self.first, -1.0);
        if rest.is_outlier(self.first, cfg) {
            rest.first = second;
            rest.first_pos = self.first_pos + 1;
            *self = rest;
        }
    }

    /// True once the run is long enough for its line to bridge wide spacing between hits.
    pub fn established(&self, cfg: &GuidanceConfig) -> bool {
        let base = cfg.min_segment_length_m.max(4.0 * cfg.line_tolerance_m);
        (self.last - self.first).norm() >= base
    }

    fn spread(&self) -> Option<Spread> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f32;
        let (mx, my) = (self.sx / n, self.sy / n);
        Some(Spread {
            centroid: self.origin + Vec2::new(mx, my),
            xx: self.sxx / n - mx * mx,
            xy: self.sxy / n - mx * my,
            yy: self.syy / n - my * my,
        })
    }

    /// The total least squares line; `None` for fewer than two distinct hits.
    pub fn line(&self) -> Option<Line> {
        let (centroid, v) = self.normal_unscaled()?;
        Some(Line {
            centroid,
            normal: v * (1.0 / v.norm()),
        })
    }

    /// Centroid and a non-zero normal of any length: enough for the per-hit test, which
    /// compares squares and needs no square root for the length.
    fn normal_unscaled(&self) -> Option<(Vec2, Vec2)> {
        let s = self.spread()?;
        // The normal is the eigenvector of the smaller eigenvalue, from whichever row of
        // (C − λI) n = 0 is better conditioned (no trigonometry in the per-hit test).
        let least = s.least();
        let a = Vec2::new(s.xy, least - s.xx);
        let b = Vec2::new(least - s.yy, s.xy);
        let v = if a.norm_squared() >= b.norm_squared() {
            a
        } else {
            b
        };
        (v.norm_squared() > 0.0).then_some((s.centroid, v))
    }

    /// True when `p` lies farther from the line fitted so far than the tolerance.
    pub fn off_line(&self, p: Vec2, cfg: &GuidanceConfig) -> bool {
        self.off_line_by(p, cfg.line_tolerance_m)
    }

    /// True when `p` sits off the line by more than three times the run's own scatter (at
    /// least a tenth of the tolerance): a hit of the next wall that the tolerance let in.
    pub fn is_outlier(&self, p: Vec2, cfg: &GuidanceConfig) -> bool {
        if self.n < 3 {
            return false;
        }
        let Some(s) = self.spread() else {
            return false;
        };
        let scatter = sqrtf(s.least().max(0.0));
        self.off_line_by(p, (3.0 * scatter).max(0.1 * cfg.line_tolerance_m))
    }

    fn off_line_by(&self, p: Vec2, tolerance_m: f32) -> bool {
        self.normal_unscaled().is_some_and(|(c, v)| {
            let d = (p - c).dot(v);
            d * d > tolerance_m * tolerance_m * v.norm_squared()
        })
    }
}
