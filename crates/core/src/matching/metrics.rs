//! The three solvers behind `icl`, `plicp` and `icp`: how each pairs a point and how it turns
//! the summed pairs into a new pose.

use super::associate::{Metric, Pass, PassStats, Tally};
use super::config::MatchConfig;
use super::linalg::sym2_eigen;
use super::line_sums::line_sums;
use super::prepared::PreparedScan;
use crate::geom::{Pose2, Vec2};
use libm::{atan2f, sqrtf};

/// Relative Levenberg damping that keeps a nearly singular solve finite.
const DAMPING: f32 = 1e-6;

/// Turns summed pairs into a new pose.
pub trait Solve: Metric {
    fn solve(&self, stats: &PassStats, pose: Pose2) -> Option<Pose2>;
}

/// Plumbline ICL: point-to-line against each reference point's fitted local line, one
/// Gauss-Newton step per pass. The Hessian is the pass's information matrix.
#[derive(Default)]
pub struct PointToLineGaussNewton {
    pub(super) gradient: [f32; 3],
}

impl Metric for PointToLineGaussNewton {
    /// Only points whose reference partner lies on a fitted line take part. A point-to-point
    /// fallback at corners would lower the near-relation error on Intel (2.3 to 1.5 cm), but on
    /// dense noisy scans (UTM-30LX, 1440 beams) it makes wrong matches that flew the simulated
    /// closed loop 3 m off.
    fn pair<const N: usize>(
        r: &PreparedScan<N>,
        j: usize,
        _q: Vec2,
        _cfg: &MatchConfig,
    ) -> Option<(Vec2, Vec2)> {
        r.line(j).normal().map(|n| (r.point(j), n))
    }

    fn add(&mut self, _p: Vec2, q: Vec2, target: Vec2, n: Vec2, w: f32, pose: Pose2) {
        let res = n.dot(q - target);
        let jt = n.dot((q - pose.translation()).perp());
        self.gradient[0] += w * n.x * res;
        self.gradient[1] += w * n.y * res;
        self.gradient[2] += w * jt * res;
    }

    /// Four points at a time in SIMD lanes, to the same sums ([`line_sums`]).
    fn sums<const N: usize>(pass: &Pass<N>) -> (Tally, Self) {
        let (tally, gradient) = line_sums(pass);
        (tally, Self { gradient })
    }
}

impl Solve for PointToLineGaussNewton {
    fn solve(&self, stats: &PassStats, pose: Pose2) -> Option<Pose2> {
        let mut h = stats.information;
        let damp = DAMPING * (h.xx + h.yy + h.tt);
        h.xx += damp;
        h.yy += damp;
        h.tt += damp;
        let d = h.inverse()?.mul(self.gradient);
        Some(Pose2::new(pose.x - d[0], pose.y - d[1], pose.theta - d[2]))
    }
}

/// PL-ICP (Censi 2008): point-to-segment between the nearest reference point and its closer
/// neighbour, minimised exactly over (t, cos, sin) with |(cos, sin)| = 1 for the pass's pairs.
#[derive(Default)]
pub struct PointToSegmentExact {
    /// Upper triangle of M = sum w a a^T for x = (tx, ty, cos, sin), row by row.
    m: [f32; 10],
    /// sum w d a, so that the cost is x^T M x - 2 v^T x + const.
    v: [f32; 4],
}

impl Metric for PointToSegmentExact {
    fn pair<const N: usize>(
        r: &PreparedScan<N>,
        j: usize,
        q: Vec2,
        cfg: &MatchConfig,
    ) -> Option<(Vec2, Vec2)> {
        let pj = r.point(j);
        let max2 = cfg.line_neighbour_m * cfg.line_neighbour_m;
        let mut best: Option<(Vec2, f32)> = None;
        for off in [-1isize, 1] {
            let Some(k) = r.neighbour(j, off) else {
                continue;
            };
            let pk = r.point(k);
            let seg2 = (pk - pj).norm_squared();
            if seg2 > max2 || seg2 == 0.0 {
                continue;
            }
            let dq = (pk - q).norm_squared();
            if best.is_none_or(|(_, b)| dq < b) {
                best = Some((pk, dq));
            }
        }
        let (pk, _) = best?;
        let d = pk - pj;
        let n = d.perp() * (1.0 / d.norm());
        Some((pj, n))
    }

    fn add(&mut self, p: Vec2, _q: Vec2, target: Vec2, n: Vec2, w: f32, _pose: Pose2) {
        let a = [n.x, n.y, n.x * p.x + n.y * p.y, n.y * p.x - n.x * p.y];
        let d = n.dot(target);
        let mut k = 0;
        for i in 0..4 {
            for j in i..4 {
                self.m[k] += w * a[i] * a[j];
                k += 1;
            }
            self.v[i] += w * d * a[i];
        }
    }
}

impl PointToSegmentExact {
    fn at(&self, i: usize, j: usize) -> f32 {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        // Offset of row i in the packed upper triangle of a 4x4 matrix.
        const ROW: [usize; 4] = [0, 4, 7, 9];
        self.m[ROW[i] + j - i]
    }
}

impl Solve for PointToSegmentExact {
    fn solve(&self, _stats: &PassStats, _pose: Pose2) -> Option<Pose2> {
        // Eliminate t: t = A^-1 (v_t - B r); the rotation part is then min r^T S r - 2 h^T r on |r| = 1.
        let (a11, a12, a22) = (self.at(0, 0), self.at(0, 1), self.at(1, 1));
        let det = a11 * a22 - a12 * a12;
        if !(det.is_finite() && det > 1e-9 * (a11 + a22) * (a11 + a22)) {
            return None;
        }
        let ai = [[a22 / det, -a12 / det], [-a12 / det, a11 / det]];
        let b = [
            [self.at(0, 2), self.at(0, 3)],
            [self.at(1, 2), self.at(1, 3)],
        ];
        // AiB = A^-1 B, and Ai v_t.
        let aib = |r: usize, c: usize| ai[r][0] * b[0][c] + ai[r][1] * b[1][c];
        let aiv = [
            ai[0][0] * self.v[0] + ai[0][1] * self.v[1],
            ai[1][0] * self.v[0] + ai[1][1] * self.v[1],
        ];
        let s = |r: usize, c: usize| {
            self.at(2 + r, 2 + c) - (b[0][r] * aib(0, c) + b[1][r] * aib(1, c))
        };
        let h = [
            self.v[2] - (b[0][0] * aiv[0] + b[1][0] * aiv[1]),
            self.v[3] - (b[0][1] * aiv[0] + b[1][1] * aiv[1]),
        ];
        let r = unit_circle_minimum(s(0, 0), 0.5 * (s(0, 1) + s(1, 0)), s(1, 1), h)?;
        let t = [
            aiv[0] - (aib(0, 0) * r.x + aib(0, 1) * r.y),
            aiv[1] - (aib(1, 0) * r.x + aib(1, 1) * r.y),
        ];
        let pose = Pose2::new(t[0], t[1], atan2f(r.y, r.x));
        pose.is_finite().then_some(pose)
    }
}

/// Minimises r^T S r - 2 h^T r over unit vectors r (S symmetric 2x2).
///
/// The minimiser is r = (S + lambda I)^-1 h for the largest lambda with |r| = 1 (lambda at least
/// minus the least eigenvalue of S): the same root Censi's closed form takes from a quartic,
/// found here by bisection on the monotone secular function, which is safer in f32.
fn unit_circle_minimum(sxx: f32, sxy: f32, syy: f32, h: [f32; 2]) -> Option<Vec2> {
    let (hi, lo, v_lo) = sym2_eigen(sxx, sxy, syy);
    let v_hi = v_lo.perp();
    let hv = Vec2::new(h[0], h[1]);
    let (b_lo, b_hi) = (hv.dot(v_lo), hv.dot(v_hi));
    let norm_at = |lambda: f32| {
        let (x, y) = (b_lo / (lo + lambda), b_hi / (hi + lambda));
        x * x + y * y
    };
    let hn = hv.norm();
    if !(hn.is_finite() && hi.is_finite()) {
        return None;
    }
    if hn == 0.0 {
        return Some(v_lo);
    }
    // |r(lambda)| <= |h| / (lo + lambda), so the root lies in (-lo, -lo + |h|].
    let (mut a, mut b) = (-lo, -lo + hn);
    for _ in 0..60 {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        if norm_at(mid) > 1.0 {
            a = mid;
        } else {
            b = mid;
        }
    }
    let lambda = b;
    let r = v_lo * (b_lo / (lo + lambda)) + v_hi * (b_hi / (hi + lambda));
    let n = r.norm();
    // In the "hard case" (h orthogonal to the least eigenvector) the residual length is made up
    // along that eigenvector.
    let r = if n < 1.0 {
        r + v_lo * sqrtf(1.0 - n * n)
    } else {
        r * (1.0 / n)
    };
    r.is_finite().then_some(r)
}

/// Point-to-point ICP with the closed-form 2-D least-squares rotation (Horn/Umeyama in 2-D).
#[derive(Default)]
pub struct PointToPointClosedForm {
    w: f32,
    p: Vec2,
    m: Vec2,
    /// Sums of w p_a m_b for a, b in {x, y}.
    pxmx: f32,
    pxmy: f32,
    pymx: f32,
    pymy: f32,
}

impl Metric for PointToPointClosedForm {
    const TO_POINT: bool = true;

    fn pair<const N: usize>(
        r: &PreparedScan<N>,
        j: usize,
        _q: Vec2,
        _cfg: &MatchConfig,
    ) -> Option<(Vec2, Vec2)> {
        Some((r.point(j), Vec2::ZERO))
    }

    fn add(&mut self, p: Vec2, _q: Vec2, m: Vec2, _n: Vec2, w: f32, _pose: Pose2) {
        self.w += w;
        self.p = self.p + p * w;
        self.m = self.m + m * w;
        self.pxmx += w * p.x * m.x;
        self.pxmy += w * p.x * m.y;
        self.pymx += w * p.y * m.x;
        self.pymy += w * p.y * m.y;
    }
}

impl Solve for PointToPointClosedForm {
    fn solve(&self, _stats: &PassStats, _pose: Pose2) -> Option<Pose2> {
        if self.w <= 0.0 {
            return None;
        }
        let pc = self.p * (1.0 / self.w);
        let mc = self.m * (1.0 / self.w);
        // Centred cross-covariance entries.
        let sxx = self.pxmx - self.w * pc.x * mc.x;
        let sxy = self.pxmy - self.w * pc.x * mc.y;
        let syx = self.pymx - self.w * pc.y * mc.x;
        let syy = self.pymy - self.w * pc.y * mc.y;
        let theta = atan2f(sxy - syx, sxx + syy);
        let rot = Pose2::new(0.0, 0.0, theta);
        let t = mc - rot.rotate(pc);
        let pose = Pose2::new(t.x, t.y, theta);
        pose.is_finite().then_some(pose)
    }
}
