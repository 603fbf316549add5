//! A reference scan's local line fits, four consecutive centres at a time in `f32x4` lanes.
//!
//! Centres `i..i + 4` have neighbours `i ± k..i ± k + 4`, four consecutive points, so each step
//! of the walk outwards is one load of four x and four y a side for all four fits; a lane that
//! meets a gap or reaches the extent stops taking points (a mask) while the others go on, and
//! the walk ends when no lane is alive. Each lane sums its neighbourhood from scratch (carrying
//! sums from one fit to the next is a chain through every centre, which lanes cannot share),
//! and the covariance, eigen decomposition and flatness test follow lane by lane.

use super::linalg::sym2_eigen_lanes;
use wide::{f32x4, CmpEq, CmpGe, CmpGt, CmpLe, CmpLt};

/// When a neighbourhood counts as a line (squared distances, m²).
pub(super) struct FitLimits {
    pub max2: f32,
    pub extent2: f32,
    pub max_flatness: f32,
}

/// Four fits: where a lane is a line (`is_line` all ones), its unit normal.
pub(super) struct Fits {
    /// How many points each fit took, the centre included (for tests of the caps).
    #[cfg(test)]
    pub count: f32x4,
    pub normal_x: f32x4,
    pub normal_y: f32x4,
    pub is_line: f32x4,
}

/// Count, first and second moments of four neighbourhoods relative to their centres.
#[derive(Default)]
struct Moments {
    n: f32x4,
    sx: f32x4,
    sy: f32x4,
    sxx: f32x4,
    sxy: f32x4,
    syy: f32x4,
}

impl Moments {
    /// Adds the offsets `(dx, dy)` of the lanes in `take` (all ones); the other lanes add zeros,
    /// which leaves their sums exactly as they were.
    #[inline(always)]
    fn add(&mut self, take: f32x4, dx: f32x4, dy: f32x4) {
        let (dx, dy) = (dx & take, dy & take);
        self.n += f32x4::ONE & take;
        self.sx += dx;
        self.sy += dy;
        self.sxx += dx * dx;
        self.sxy += dx * dy;
        self.syy += dy * dy;
    }
}

/// `v[from..from + 4]` as lanes: one unaligned load.
#[inline(always)]
pub(super) fn lane(v: &[f32], from: usize) -> f32x4 {
    let q = &v[from..from + 4];
    f32x4::from([q[0], q[1], q[2], q[3]])
}

/// The least neighbour cap whose walks begin with unmasked steps (see [`walk`]): on sparse
/// scans (8 a side) a walk reaches the extent in two or three steps, and the unmasked steps
/// cost more than they saved (office-360 line fits 40.8 k -> 45.5 k instructions a match).
const UNMASKED_FROM: usize = 16;

/// One side's walk outwards from the centres `c`, `neighbour(k)` being the points `k` places
/// away: each lane takes its neighbours nearest first (adding them to `m`) up to a gap (a
/// neighbour farther than the neighbour limit, left out), or until it has taken one at the
/// extent or beyond and two at least, or `cap` (when given: per lane, the most it may take).
/// The walk ends when no lane is alive.
///
/// Uncapped and long enough, the walk first takes whole steps while every lane's neighbour is
/// nearer than both the extent and the neighbour limit, so that every lane takes it and goes
/// on: no masks, the squares of the distance reused as the moments' squares, the count a step
/// counter (24 instructions a step against 31; on office-1440 about 8.6 of a walk's 10 or so
/// steps). The step where some lane stops, and those after it, are the masked general steps.
/// Two steps share one check (the second's offsets wasted when the first stops a lane, once a
/// walk): office-1440 line fits 253.6 k -> 250.3 k instructions a match.
/// The sums are the same adds in the same order: a lane that takes adds exactly what a masked
/// step adds, and counts are integers, exact in `f32`.
#[inline(always)]
fn walk<const M: usize>(
    m: &mut Moments,
    (cx, cy): (f32x4, f32x4),
    neighbour: impl Fn(usize) -> (f32x4, f32x4),
    cap: Option<f32x4>,
    lim: &FitLimits,
) {
    let (max2, extent2) = (f32x4::splat(lim.max2), f32x4::splat(lim.extent2));
    let offsets = |k: usize| {
        let (x, y) = neighbour(k);
        let (dx, dy) = (x - cx, y - cy);
        let (xx, yy) = (dx * dx, dy * dy);
        (dx, dy, xx, yy, xx + yy)
    };
    let mut k = 1;
    if cap.is_none() && M >= UNMASKED_FROM {
        // `d2 < go_on` must mean both `d2 <= max2` and `d2 < extent2` (NaN limits: never).
        let go_on = f32x4::splat(if lim.extent2 <= lim.max2 {
            lim.extent2
        } else if lim.max2 < lim.extent2 {
            lim.max2
        } else {
            f32::NAN
        });
        let mut add = |(dx, dy, xx, yy, _): (f32x4, f32x4, f32x4, f32x4, f32x4)| {
            m.sx += dx;
            m.sy += dy;
            m.sxx += xx;
            m.sxy += dx * dy;
            m.syy += yy;
        };
        while k < M {
            let (a, b) = (offsets(k), offsets(k + 1));
            let (go_a, go_b) = (a.4.cmp_lt(go_on), b.4.cmp_lt(go_on));
            if (go_a & go_b).move_mask() != 0b1111 {
                if go_a.move_mask() == 0b1111 {
                    add(a);
                    k += 1;
                }
                break;
            }
            add(a);
            add(b);
            k += 2;
        }
        m.n += f32x4::splat((k as i32 - 1) as f32);
    }
    let mut alive = f32x4::ZERO.cmp_eq(f32x4::ZERO);
    while k <= M {
        if let Some(cap) = cap {
            alive &= f32x4::splat(k as f32).cmp_le(cap);
        }
        let (dx, dy, _, _, d2) = offsets(k);
        let take = alive & d2.cmp_le(max2);
        m.add(take, dx, dy);
        // A lane alive at step k has taken k - 1, so "two at least" is k >= 2.
        alive = if k >= 2 {
            take & d2.cmp_lt(extent2)
        } else {
            take
        };
        if !alive.any() {
            break;
        }
        k += 1;
    }
}

/// The fits of the four centres at `M..M + 4` of the windows `xs` and `ys` (`2 * M + 4`
/// points, the centres' `M` neighbours below and above), whose moments are those of the
/// neighbours each side's [`walk`] takes. `caps`, when given, is how many neighbours each
/// lane may take below and above (near the ends of a scan, or round a small ring); without it
/// every lane may take `M`. A fit is a line when it has three points at least and the spread
/// across is at most `max_flatness` of the spread along.
#[inline(always)]
pub(super) fn fit4<const M: usize>(
    xs: &[f32],
    ys: &[f32],
    caps: Option<(f32x4, f32x4)>,
    lim: &FitLimits,
) -> Fits {
    let (xs, ys) = (&xs[..2 * M + 4], &ys[..2 * M + 4]);
    let at = |j: usize| (lane(xs, j), lane(ys, j));
    let centre = at(M);
    // Sums relative to the centres, which count themselves and add zero offsets.
    let mut m = Moments {
        n: f32x4::ONE,
        ..Moments::default()
    };
    // All of one side, then all of the other: the order the scalar definition sums in.
    walk::<M>(&mut m, centre, |k| at(M - k), caps.map(|c| c.0), lim);
    walk::<M>(&mut m, centre, |k| at(M + k), caps.map(|c| c.1), lim);
    let inv_n = f32x4::ONE / m.n;
    let (mx, my) = (m.sx * inv_n, m.sy * inv_n);
    let (cxx, cxy, cyy) = (
        m.sxx * inv_n - mx * mx,
        m.sxy * inv_n - mx * my,
        m.syy * inv_n - my * my,
    );
    let (hi, lo, normal_x, normal_y) = sym2_eigen_lanes(cxx, cxy, cyy);
    let is_line = m.n.cmp_ge(f32x4::splat(3.0))
        & hi.cmp_gt(f32x4::ZERO)
        & lo.cmp_le(f32x4::splat(lim.max_flatness) * hi);
    Fits {
        #[cfg(test)]
        count: m.n,
        normal_x,
        normal_y,
        is_line,
    }
}
