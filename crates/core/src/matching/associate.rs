//! One association pass: every current point, moved by the pose estimate, finds its partner in
//! the reference through angular projection; gating, the seed 000 sec. 4.2 test and a robust
//! weight decide how much it counts; a metric-specific accumulator sums it up.

use super::config::MatchConfig;
use super::linalg::Sym3;
use super::prepared::PreparedScan;
use crate::geom::{Pose2, Vec2};

/// What a metric contributes: how it pairs a point and how it sums pairs for its solver.
pub trait Metric: Default {
    /// Pairs are points without a normal (point-to-point); known at compile time so the
    /// point-to-line metrics' hot loop has no branch on it.
    const TO_POINT: bool = false;
    /// The partner of `q` (current point in the reference frame) near reference point `j`:
    /// `(target point, unit normal)` for point-to-line, normal zero for point-to-point.
    fn pair<const N: usize>(
        reference: &PreparedScan<N>,
        j: usize,
        q: Vec2,
        cfg: &MatchConfig,
    ) -> Option<(Vec2, Vec2)>;
    /// Sums one weighted pair (`p` in the current frame, `q` = pose applied to `p`).
    fn add(&mut self, p: Vec2, q: Vec2, target: Vec2, normal: Vec2, w: f32, pose: Pose2);
}

/// Residual of a pair: distance to the point for a point-to-point metric, else to the line.
fn residual<M: Metric>(q: Vec2, target: Vec2, normal: Vec2) -> f32 {
    if M::TO_POINT {
        (q - target).norm()
    } else {
        normal.dot(q - target)
    }
}

/// Statistics of a pass, and the information matrix of the pose for the quality report.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassStats {
    pub inliers: u16,
    pub weighted_sq_sum: f32,
    pub weight_sum: f32,
    pub sq_sum: f32,
    pub rejected_dynamic: u16,
    /// Information (J^T W J) of (x, y, theta) at the pose of the pass.
    pub information: Sym3,
    /// A robust standard deviation of the residual (1.4826 x median |r|), for the next gate.
    pub robust_sigma: f32,
}

/// Bins of the residual histogram that gives the median without sorting or storing residuals.
const HIST_BINS: usize = 32;

/// How the pass gates and weights.
#[derive(Clone, Copy)]
pub struct PassGate {
    /// Largest accepted residual (and, first pass, point distance), m.
    pub gate_m: f32,
    /// Cauchy kernel width, m; residuals well below it weigh about 1.
    pub kernel_m: f32,
    /// Seed 000 sec. 4.2 threshold on J = r², or `None` when the test is off.
    pub dynamic_threshold_m2: Option<f32>,
}

/// Marks a current point that found no partner in the last pass.
pub const NO_PARTNER: u16 = u16::MAX;

/// Each current point's reference partner from the previous pass. Between passes the pose moves
/// little, so the partner's neighbourhood is where to look again: later passes skip the bearing
/// projection (an atan2 per point) and search the window around the old partner instead.
pub struct Partners<'a> {
    pub slots: &'a mut [u16],
    /// Use the slots as search seeds (false on a first pass: they belong to another match).
    pub reuse: bool,
}

pub fn associate<M: Metric, const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    pose: Pose2,
    gate: &PassGate,
    cfg: &MatchConfig,
    partners: Partners,
) -> (PassStats, M) {
    let (s, c) = (libm::sinf(pose.theta), libm::cosf(pose.theta));
    let moved = |p: Vec2| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y);
    let points = current.points();
    let slots = &mut partners.slots[..points.len()];
    find_partners(reference, points, moved, pose, cfg, slots, partners.reuse);
    // The sums in a loop of their own, with no calls in it, so they stay in registers.
    let mut stats = PassStats::default();
    let mut acc = M::default();
    let mut hist = [0u16; HIST_BINS];
    let bin_width = gate.gate_m / HIST_BINS as f32;
    let bins_per_m = 1.0 / bin_width;
    let gate2 = gate.gate_m * gate.gate_m;
    let point_gate2 = cfg.max_correspondence_m * cfg.max_correspondence_m;
    let inv_k2 = 1.0 / (gate.kernel_m * gate.kernel_m);
    for (&p, &j) in points.iter().zip(slots.iter()) {
        if j == NO_PARTNER {
            continue;
        }
        let j = j as usize;
        let rp = moved(p);
        let q = rp + pose.translation();
        // Exactly the distance the search found (finite: the search skips NaN and infinity).
        if (q - reference.point(j)).norm_squared() > point_gate2 {
            continue;
        }
        let Some((target, normal)) = M::pair(reference, j, q, cfg) else {
            continue;
        };
        let r = residual::<M>(q, target, normal);
        let r2 = r * r;
        if gate.dynamic_threshold_m2.is_some_and(|t| r2 > t) {
            stats.rejected_dynamic += 1;
            continue;
        }
        if r2 > gate2 {
            continue;
        }
        let w = 1.0 / (1.0 + r2 * inv_k2);
        acc.add(p, q, target, normal, w, pose);
        // |r| is within the gate, so the bin is too (but for rounding at its very edge).
        let bin = ((r.abs() * bins_per_m) as i32).min(HIST_BINS as i32 - 1) as usize;
        hist[bin] = hist[bin].saturating_add(1);
        stats.inliers += 1;
        stats.weighted_sq_sum += w * r2;
        stats.weight_sum += w;
        stats.sq_sum += r2;
        let drp = rp.perp();
        if M::TO_POINT {
            stats.information.add_outer([1.0, 0.0, drp.x], w);
            stats.information.add_outer([0.0, 1.0, drp.y], w);
        } else {
            stats
                .information
                .add_outer([normal.x, normal.y, normal.dot(drp)], w);
        }
    }
    stats.robust_sigma = 1.4826 * histogram_median(&hist, stats.inliers, bin_width);
    (stats, acc)
}

/// Each point's nearest reference point (or [`NO_PARTNER`]) into `slots`: searched around the
/// slot's old partner when `reuse`, else around the point's bearing.
fn find_partners<const N: usize>(
    reference: &PreparedScan<N>,
    points: &[Vec2],
    moved: impl Fn(Vec2) -> Vec2,
    pose: Pose2,
    cfg: &MatchConfig,
    slots: &mut [u16],
    reuse: bool,
) {
    let half = cfg.search_half_window as usize;
    let mut hint = 0;
    for (&p, slot) in points.iter().zip(slots.iter_mut()) {
        let q = moved(p) + pose.translation();
        let k = match *slot {
            k if reuse && k != NO_PARTNER => Some(k as usize),
            _ => reference.project(q, hint).inspect(|&k| hint = k),
        };
        let found = k.and_then(|k| reference.nearest_in_window(q, k, half));
        *slot = found.map_or(NO_PARTNER, |(j, _)| j as u16);
    }
}

fn histogram_median(hist: &[u16; HIST_BINS], count: u16, bin_width: f32) -> f32 {
    let half = count.div_ceil(2);
    let mut seen = 0u16;
    for (i, &h) in hist.iter().enumerate() {
        if seen + h >= half && h > 0 {
            let into = (half - seen) as f32 / h as f32;
            return bin_width * (i as f32 + into);
        }
        seen += h;
    }
    0.0
}
