//! One association pass: every current point, moved by the pose estimate, finds its partner in
//! the reference through angular projection; gating, the seed 000 sec. 4.2 test and a robust
//! weight decide how much it counts; a metric-specific accumulator sums it up.

use super::config::MatchConfig;
use super::linalg::Sym3;
use super::prepared::PreparedScan;
use super::window::{nearest_around, six_around, usual_query};
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
    /// Gates, weighs and sums a pass whose partners are found: point by point through
    /// [`Metric::pair`] and [`Metric::add`], unless the metric has a faster way to the same sums.
    fn sums<const N: usize>(pass: &Pass<N>) -> (Tally, Self) {
        point_by_point(pass)
    }
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
pub const HIST_BINS: usize = 32;

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

/// A pass whose partners are found, and how it gates and weighs them.
pub struct Pass<'a, const N: usize> {
    pub reference: &'a PreparedScan<N>,
    pub points: &'a [Vec2],
    /// Each point's partner in `reference`, or [`NO_PARTNER`].
    pub slots: &'a [u16],
    pub pose: Pose2,
    pub cfg: &'a MatchConfig,
    /// Sine and cosine of the pose's heading.
    pub sin: f32,
    pub cos: f32,
    /// Squared gates: on the distance to the partner, and on the residual.
    pub point_gate2: f32,
    pub gate2: f32,
    /// Seed 000 sec. 4.2 threshold on r², infinite when the test is off (no r² exceeds it).
    pub dynamic2: f32,
    /// 1 / (Cauchy kernel width)².
    pub inv_k2: f32,
    /// Residual histogram bins per metre.
    pub bins_per_m: f32,
}

impl<const N: usize> Pass<'_, N> {
    /// `p` rotated by the pose's heading (not yet translated).
    #[inline(always)]
    pub fn rotated(&self, p: Vec2) -> Vec2 {
        let (s, c) = (self.sin, self.cos);
        Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y)
    }
}

/// A pass's statistics (all but the robust sigma) and its residual histogram.
#[derive(Default)]
pub struct Tally {
    pub stats: PassStats,
    pub hist: [u16; HIST_BINS],
}

pub fn associate<M: Metric, const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    pose: Pose2,
    gate: &PassGate,
    cfg: &MatchConfig,
    partners: Partners,
) -> (PassStats, M) {
    let points = current.points();
    let bin_width = gate.gate_m / HIST_BINS as f32;
    let pass = Pass {
        reference,
        points,
        // Filled in below, once the partners are found.
        slots: &[],
        pose,
        cfg,
        sin: libm::sinf(pose.theta),
        cos: libm::cosf(pose.theta),
        point_gate2: cfg.max_correspondence_m * cfg.max_correspondence_m,
        gate2: gate.gate_m * gate.gate_m,
        dynamic2: gate.dynamic_threshold_m2.unwrap_or(f32::INFINITY),
        inv_k2: 1.0 / (gate.kernel_m * gate.kernel_m),
        bins_per_m: 1.0 / bin_width,
    };
    let slots = &mut partners.slots[..points.len()];
    find_partners(&pass, slots, partners.reuse);
    let pass = Pass {
        slots: &*slots,
        ..pass
    };
    let (Tally { mut stats, hist }, acc) = M::sums(&pass);
    stats.robust_sigma = 1.4826 * histogram_median(&hist, stats.inliers, bin_width);
    (stats, acc)
}

/// [`Metric::sums`] point by point. In a loop of its own, with no calls in it, so the sums stay
/// in registers.
pub fn point_by_point<M: Metric, const N: usize>(pass: &Pass<N>) -> (Tally, M) {
    let mut tally = Tally::default();
    let stats = &mut tally.stats;
    let mut acc = M::default();
    let t = pass.pose.translation();
    for (&p, &j) in pass.points.iter().zip(pass.slots) {
        if j == NO_PARTNER {
            continue;
        }
        let j = j as usize;
        let rp = pass.rotated(p);
        let q = rp + t;
        // Exactly the distance the search found (finite: the search skips NaN and infinity).
        if (q - pass.reference.point(j)).norm_squared() > pass.point_gate2 {
            continue;
        }
        let Some((target, normal)) = M::pair(pass.reference, j, q, pass.cfg) else {
            continue;
        };
        let r = residual::<M>(q, target, normal);
        let r2 = r * r;
        if r2 > pass.dynamic2 {
            stats.rejected_dynamic += 1;
            continue;
        }
        if r2 > pass.gate2 {
            continue;
        }
        let w = 1.0 / (1.0 + r2 * pass.inv_k2);
        acc.add(p, q, target, normal, w, pass.pose);
        // |r| is within the gate, so the bin is too (but for rounding at its very edge).
        let bin = ((r.abs() * pass.bins_per_m) as i32).min(HIST_BINS as i32 - 1) as usize;
        tally.hist[bin] = tally.hist[bin].saturating_add(1);
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
    (tally, acc)
}

/// Each point's nearest reference point (or [`NO_PARTNER`]) into `slots`: searched around the
/// slot's old partner when `reuse`, else around the point's bearing.
fn find_partners<const N: usize>(pass: &Pass<N>, slots: &mut [u16], reuse: bool) {
    let half = pass.cfg.search_half_window as usize;
    let t = pass.pose.translation();
    let reference = pass.reference.points();
    let mut hint = 0;
    for (&p, slot) in pass.points.iter().zip(slots.iter_mut()) {
        let q = pass.rotated(p) + t;
        // The usual queries in one go, without the general path's checks and branches: a
        // window inside the scan around the old partner, or where the walk moves up one point.
        if half == 3 {
            let old = *slot as usize;
            if reuse && *slot != NO_PARTNER {
                if let Some(window) = six_around(reference, old) {
                    *slot = nearest_around(window, old, q).map_or(NO_PARTNER, |j| j as u16);
                    continue;
                }
            } else if let Some((k, j)) = usual_query(reference, q, hint) {
                hint = k;
                *slot = j.map_or(NO_PARTNER, |j| j as u16);
                continue;
            }
        }
        let k = match *slot {
            k if reuse && k != NO_PARTNER => Some(k as usize),
            _ => pass.reference.project(q, hint).inspect(|&k| hint = k),
        };
        let found = k.and_then(|k| pass.reference.nearest_in_window(q, k, half));
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
