//! The ends of walls (door frames, openings, the edge of a cabinet): what pins a corridor's
//! axis when the point-to-line metric cannot.
//!
//! Point-to-line residuals see a wall only across it, so in a corridor their information along
//! the axis is the noise of the fitted normals (a few thousandths of the information across,
//! measured on the simulator's office with the XV-11), and the solution there is not a
//! measurement. Where a wall ends, its end is a point both scans see at the same place in the
//! world: the last return on the wall lies inside the true end by less than one beam spacing
//! on that wall, which each scan measures for itself (the gap to the return before it). Pairing
//! the ends of the two scans gives the motion along the axis with a variance that follows from
//! those spacings, not from a tuned constant.
//!
//! An end counts only where the scan shows why the wall stops: the next beam passes the end
//! and returns from much farther (the wall occludes what is behind it), or it returns nothing
//! while the end is well inside the lidar's reach. The last returns at the scan's reach are
//! where the range runs out, not where the wall does, so a featureless corridor has no ends
//! and its axis stays unobserved.

use super::config::MatchConfig;
use super::prepared::PreparedScan;
use crate::geom::{normalize_angle, Pose2, Vec2};

/// Ends kept per scan (the nearest to the lidar, whose beams are densest on the wall).
const MAX_ENDS: usize = 32;
/// An end without a farther return behind it counts only within this share of the farthest
/// return of its scan: beyond, the wall may simply leave the lidar's reach.
const REACH_SHARE: f32 = 0.9;
/// The next return is the next beam's when the bearing gap is below this many beam steps.
const GAP_STEPS: f32 = 1.5;
/// A wall ends where returns stop for more than this many beam steps: single dropouts (a few
/// per cent of beams on a cheap lidar) leave a wall whole.
const MISSING_BEAMS: f32 = 4.0;
/// Least cosine of incidence at the last return: nearer grazing the wall may go on unseen.
const MIN_INCIDENCE_COS: f32 = 0.25;
/// A wall's direction at its end is taken over a chord at least this long, m, and at most
/// this many beams (a dense lidar's beams fall a few millimetres apart on a near wall).
const WALL_CHORD_M: f32 = 0.15;
const WALL_MAX_STEPS: usize = 64;
/// Farthest a return may lie off that chord for the run to count as straight, m.
const WALL_STRAIGHT_M: f32 = 0.05;
/// Least cosine between the two ends' directions for them to be the same end.
const SAME_END_COS: f32 = 0.8;
/// Least |cos| between an end's wall and the direction being measured: a wall across that
/// direction is the line metric's to measure.
const ALONG_COS: f32 = 0.7;
/// Largest offset across the measured direction between paired ends, m: the line metric has
/// already placed the scan across it to a few millimetres.
const ACROSS_GATE_M: f32 = 0.1;
/// Range noise of one return, m, added to the spacing's part of each pair's variance.
const POINT_SIGMA_M: f32 = 0.005;
/// Fewest agreeing pairs for the direction to count as observed: with three, one wrong pairing
/// (clutter, a person) is outvoted by the median; with two it decides half the time. On the
/// Intel log two let such pairings in (relation error 0.0180 -> 0.0193 m; two anywhere on this
/// main: 0.0355 -> 0.0546 m); three leave it as it was. Two do count when they lie on opposite
/// sides of the lidar across the direction ([`Pair::side_m`]): the walls either side of a
/// corridor ending at an opening or a cross corridor, often the only ends a short-reach lidar
/// has there. Those are two structures, not the two jambs of one door that a wrong pose
/// misplaces together, and each pair must agree with the other within three of its own
/// standard deviations.
const MIN_PAIRS: usize = 3;
/// Pairings made, each at the pose the previous one found.
const ROUNDS: usize = 2;

/// Where a wall ends in one scan's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct WallEnd {
    /// The estimated end: the last return moved out by half the beam spacing on the wall.
    pub end: Vec2,
    /// Unit direction along the wall, out past its end.
    pub out: Vec2,
    /// Distance between the last two returns on the wall, m: the end is known to within it.
    pub spacing_m: f32,
}

/// What the wall ends measured along one direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlongMeasurement {
    /// Motion to add along the direction, m.
    pub shift_m: f32,
    /// Variance of the motion along it, m².
    pub variance_m2: f32,
    /// Pairs of ends that agreed.
    pub pairs: usize,
}

/// The wall ends of `scan` (see the module documentation), at most [`MAX_ENDS`], nearest first
/// kept. Returns how many were written to `out`.
pub(super) fn wall_ends<const N: usize>(
    scan: &PreparedScan<N>,
    cfg: &MatchConfig,
    out: &mut [WallEnd; MAX_ENDS],
) -> usize {
    let points = scan.points();
    let reach = points.iter().map(|p| p.norm()).fold(0.0, f32::max);
    let mut count = 0;
    for i in 0..points.len() {
        for side in [1isize, -1] {
            let Some(end) = wall_end_at(scan, i, side, reach, cfg) else {
                continue;
            };
            if count < MAX_ENDS {
                out[count] = end;
                count += 1;
            } else if let Some(far) = farthest(&out[..count]) {
                if end.end.norm_squared() < out[far].end.norm_squared() {
                    out[far] = end;
                }
            }
        }
    }
    count
}

fn farthest(ends: &[WallEnd]) -> Option<usize> {
    (0..ends.len()).max_by(|&a, &b| {
        ends[a]
            .end
            .norm_squared()
            .total_cmp(&ends[b].end.norm_squared())
    })
}

/// Point `i` as the end of a wall that runs towards `-side` in angular order, if it is one.
fn wall_end_at<const N: usize>(
    scan: &PreparedScan<N>,
    i: usize,
    side: isize,
    reach: f32,
    cfg: &MatchConfig,
) -> Option<WallEnd> {
    let (j, j2) = (scan.neighbour(i, side)?, scan.neighbour(i, 2 * side)?);
    let p = scan.point(i);
    let on_wall = |d: Vec2| d.norm() <= cfg.line_neighbour_m;
    // Where the next return lies on the wall nearby, the wall goes on (most points: checked
    // first because it is cheap).
    if on_wall(scan.point(j) - p) {
        return None;
    }
    let (out, spacing_m, beam_step) = wall_behind(scan, i, side, cfg)?;
    let range = p.norm();
    // A beam meeting the wall near grazing may be the last the lidar returns from it.
    if out.perp().dot(p).abs() < MIN_INCIDENCE_COS * range {
        return None;
    }
    let open_step = bearing_step(scan, j, i);
    let missing_returns = open_step > MISSING_BEAMS * beam_step && range < REACH_SHARE * reach;
    let behind = |q: usize| {
        let q = scan.point(q);
        q.norm() > range + cfg.line_neighbour_m && !on_wall(q - p)
    };
    let occludes = open_step <= GAP_STEPS * beam_step && behind(j) && behind(j2);
    if !(missing_returns || occludes) {
        return None;
    }
    Some(WallEnd {
        end: p + out * (0.5 * spacing_m),
        out,
        spacing_m,
    })
}

fn bearing_step<const N: usize>(scan: &PreparedScan<N>, a: usize, b: usize) -> f32 {
    normalize_angle(scan.bearings[a] - scan.bearings[b]).abs()
}

/// The wall that point `i` ends, traced back towards `-side` over at least [`WALL_CHORD_M`]
/// (a single step between returns a few centimetres apart is mostly range noise): its unit
/// direction out past `i`, the mean spacing of its returns and the least beam step on it.
/// `None` unless the returns run on without a gap and stay on the chord.
fn wall_behind<const N: usize>(
    scan: &PreparedScan<N>,
    i: usize,
    side: isize,
    cfg: &MatchConfig,
) -> Option<(Vec2, f32, f32)> {
    let p = scan.point(i);
    let (mut previous, mut beam_step) = (i, f32::INFINITY);
    for steps in 1..=WALL_MAX_STEPS {
        let k = scan.neighbour(i, -(steps as isize) * side)?;
        let (q, last) = (scan.point(k), scan.point(previous));
        if (last - q).norm() > cfg.line_neighbour_m {
            return None;
        }
        beam_step = beam_step.min(bearing_step(scan, previous, k));
        previous = k;
        let chord = p - q;
        let length = chord.norm();
        if length < WALL_CHORD_M || steps < 2 {
            continue;
        }
        let out = chord * (1.0 / length);
        let straight = (1..steps).all(|m| {
            scan.neighbour(i, -(m as isize) * side)
                .is_some_and(|n| (scan.point(n) - q).cross(out).abs() <= WALL_STRAIGHT_M)
        });
        return straight.then_some((out, length / steps as f32, beam_step));
    }
    None
}

/// The motion along the unit direction `along` (reference frame) that brings the current
/// scan's wall ends onto the reference's, from `motion`; `None` when fewer than [`MIN_PAIRS`]
/// pairs agree (a featureless corridor).
pub fn measure_along<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    motion: Pose2,
    along: Vec2,
    cfg: &MatchConfig,
) -> Option<AlongMeasurement> {
    let mut ref_ends = [WallEnd::default(); MAX_ENDS];
    let mut cur_ends = [WallEnd::default(); MAX_ENDS];
    let ref_count = wall_ends(reference, cfg, &mut ref_ends);
    let cur_count = wall_ends(current, cfg, &mut cur_ends);
    let (ref_ends, cur_ends) = (&ref_ends[..ref_count], &cur_ends[..cur_count]);
    let mut shift_m = 0.0;
    let mut found = None;
    for _ in 0..ROUNDS {
        let at = Pose2::new(
            motion.x + along.x * shift_m,
            motion.y + along.y * shift_m,
            motion.theta,
        );
        let step = paired_shift(ref_ends, cur_ends, at, along, cfg)?;
        shift_m += step.shift_m;
        found = Some(AlongMeasurement { shift_m, ..step });
    }
    found.filter(|m| m.shift_m.abs() <= cfg.max_correspondence_m)
}

/// One pairing of the ends at `at`: the robust weighted mean of the pairs' offsets along
/// `along`, and its variance.
fn paired_shift(
    ref_ends: &[WallEnd],
    cur_ends: &[WallEnd],
    at: Pose2,
    along: Vec2,
    cfg: &MatchConfig,
) -> Option<AlongMeasurement> {
    // (offset along, variance) of each pair.
    let mut pairs = [Pair::default(); MAX_ENDS];
    let mut n = 0;
    for c in cur_ends {
        let (end, out) = (at.transform(c.end), at.rotate(c.out));
        let cos = out.dot(along);
        if cos.abs() < ALONG_COS {
            continue;
        }
        let nearest = ref_ends
            .iter()
            .filter(|r| r.out.dot(out) >= SAME_END_COS)
            .filter(|r| (r.end - end).dot(along.perp()).abs() <= ACROSS_GATE_M)
            .map(|r| (r, (r.end - end).dot(along)))
            .filter(|(_, d)| d.abs() <= cfg.max_correspondence_m)
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
        if let Some((r, d)) = nearest {
            let spacing2 = r.spacing_m * r.spacing_m + c.spacing_m * c.spacing_m;
            let variance = cos * cos * spacing2 / 12.0 + 2.0 * POINT_SIGMA_M * POINT_SIGMA_M;
            pairs[n] = Pair {
                offset_m: d,
                variance_m2: variance,
                side_m: r.end.dot(along.perp()),
            };
            n += 1;
        }
    }
    robust_mean(&mut pairs[..n])
}

/// One paired end: its offset along the measured direction and the offset's variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Pair {
    offset_m: f32,
    variance_m2: f32,
    /// Where the reference's end lies across the direction, signed, from the lidar, m.
    side_m: f32,
}

/// The weighted mean of the offsets that agree with their weighted median to within three
/// of their own standard deviations, with its variance (inflated when they scatter more than
/// their variances say); `None` unless [`MIN_PAIRS`] agree, or two on opposite sides.
fn robust_mean(pairs: &mut [Pair]) -> Option<AlongMeasurement> {
    if pairs.len() < 2 {
        return None;
    }
    pairs.sort_unstable_by(|a, b| a.offset_m.total_cmp(&b.offset_m));
    let total: f32 = pairs.iter().map(|p| 1.0 / p.variance_m2).sum();
    let mut cumulative = 0.0;
    let median = pairs
        .iter()
        .find(|p| {
            cumulative += 1.0 / p.variance_m2;
            cumulative >= 0.5 * total
        })
        .map(|p| p.offset_m)?;
    let agrees = |p: &&Pair| (p.offset_m - median).abs() <= 3.0 * libm::sqrtf(p.variance_m2);
    let (count, weight, weighted) =
        pairs
            .iter()
            .filter(agrees)
            .fold((0usize, 0.0f32, 0.0f32), |(n, w, s), p| {
                (
                    n + 1,
                    w + 1.0 / p.variance_m2,
                    s + p.offset_m / p.variance_m2,
                )
            });
    let both_sides = pairs.iter().filter(agrees).any(|p| p.side_m > 0.0)
        && pairs.iter().filter(agrees).any(|p| p.side_m < 0.0);
    if count < MIN_PAIRS && !(count == 2 && both_sides) {
        return None;
    }
    let mean = weighted / weight;
    let chi2: f32 = pairs
        .iter()
        .filter(agrees)
        .map(|p| (p.offset_m - mean) * (p.offset_m - mean) / p.variance_m2)
        .sum();
    let scatter = (chi2 / (count - 1) as f32).max(1.0);
    Some(AlongMeasurement {
        shift_m: mean,
        variance_m2: scatter / weight,
        pairs: count,
    })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn the_mean_leaves_out_an_offset_the_others_disagree_with() {
        // Three ends 1 cm apart at about 2 cm, one pairing 30 cm off (a wrong end).
        let v = 1e-4;
        let mut pairs = on_one_side(&[(0.02, v), (0.03, v), (0.025, v), (0.33, v)]);
        let m = robust_mean(&mut pairs).unwrap();
        assert_eq!(m.pairs, 3);
        assert!((m.shift_m - 0.025).abs() < 1e-6, "{m:?}");
        // The three scatter by about their own sigma (1 cm): the variance is the mean's.
        assert!((m.variance_m2 - v / 3.0).abs() < 1e-6, "{m:?}");
    }

    #[test]
    fn the_variance_grows_when_the_offsets_scatter_more_than_their_own_variances() {
        let v = 1e-6; // 1 mm each, but 2 cm apart
        let mut pairs = on_one_side(&[(0.0, v), (0.02, v), (0.04, v), (0.02, v)]);
        // 3 sigma is 3 mm: only the two at 2 cm agree with the median, too few.
        assert!(robust_mean(&mut pairs).is_none());
        let v = 1e-4;
        let mut pairs = on_one_side(&[(0.0, v), (0.02, v), (0.04, v)]);
        let m = robust_mean(&mut pairs).unwrap();
        // chi2 = (4 + 0 + 4) cm^2 / 1 cm^2 = 8 over 2 degrees of freedom: 4 times v / 3.
        assert!((m.variance_m2 - 4.0 * v / 3.0).abs() < 1e-7, "{m:?}");
    }

    /// Pairs of (offset, variance) whose ends all lie on one side of the lidar.
    fn on_one_side(pairs: &[(f32, f32)]) -> std::vec::Vec<Pair> {
        pairs
            .iter()
            .map(|&(offset_m, variance_m2)| Pair {
                offset_m,
                variance_m2,
                side_m: 1.0,
            })
            .collect()
    }

    #[test]
    fn two_pairs_on_one_side_are_not_enough() {
        let mut pairs = on_one_side(&[(0.01, 1e-4), (0.012, 1e-4)]);
        assert!(robust_mean(&mut pairs).is_none());
    }

    #[test]
    fn two_agreeing_pairs_on_opposite_sides_measure_the_direction() {
        // The two walls of a corridor ending at a cross corridor, one either side.
        let mut pairs = on_one_side(&[(0.01, 1e-4), (0.012, 1e-4)]);
        pairs[1].side_m = -1.0;
        let m = robust_mean(&mut pairs).unwrap();
        assert_eq!(m.pairs, 2);
        assert!((m.shift_m - 0.011).abs() < 1e-6, "{m:?}");
        // Opposite sides, but 10 cm apart at 1 cm each: they disagree, and one is left.
        pairs[1].offset_m = 0.11;
        assert!(robust_mean(&mut pairs).is_none());
    }
}
