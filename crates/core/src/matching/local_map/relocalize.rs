//! Coming back to mapped space: a search for the pose at which a keyframe lines up with the
//! walls mapped long ago, so drift picked up on the way round a loop is taken out in one step.
//!
//! The refinement only looks a few centimetres around its guess, and near the end of a loop its
//! guess is off by tens of centimetres to a metre: it then lines the scan up with the walls it
//! has just mapped itself (which carry the same drift) and the old walls of the same corridor
//! are mapped again beside themselves. The search scores a window of poses against the old
//! walls only (cells whose points are on average at least `min_age` keyframes old) with a soft inlier count, the idea of
//! correlative scan matching (Olson 2009) on the line map, and accepts the best pose only if it
//! is clearly better than the guess and clearly better than any distinct alternative: in a
//! corridor, where poses along the axis score alike, it declines.

use super::cells::LineMap;
use crate::geom::{normalize_angle, Pose2, Vec2};
use crate::matching::linalg::sym2_eigen;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelocalizeConfig {
    /// Search at every this many keyframes (about every 1.5 m at the default keyframe spacing).
    pub every_keyframes: u32,
    /// A found pose closer to the guess than this (m, rad) is left to the refinement.
    pub min_jump_m: f32,
    pub min_jump_rad: f32,
    /// Half-width of the translation window, m, and its step.
    pub window_m: f32,
    pub step_m: f32,
    /// Half-width of the heading window, rad, and its step.
    pub window_rad: f32,
    pub step_rad: f32,
    /// Points scored per pose at most (every k-th point of a denser scan): the search visits
    /// thousands of poses, and a hundred-odd points already tell walls apart.
    pub max_scored_points: usize,
    /// Distance to an old wall at which a point stops counting, m (soft count, linear fall-off).
    pub inlier_m: f32,
    /// Cells whose points are younger than this on average are the vehicle's own recent
    /// (drifted) map and are not searched against.
    pub min_age: u32,
    /// The best pose must explain at least this fraction of the scan's points…
    pub min_score_ratio: f32,
    /// …by this factor more than the guess does…
    pub min_gain: f32,
    /// …and the poses scoring at least this fraction of the best…
    pub max_ambiguity: f32,
    /// …may spread at most this far across their main axis (a corridor's axis may stay
    /// open), m…
    pub max_across_spread_m: f32,
    /// …and this far in heading, rad.
    pub max_turn_spread_rad: f32,
}

impl Default for RelocalizeConfig {
    fn default() -> Self {
        Self {
            every_keyframes: 5,
            min_jump_m: 0.15,
            min_jump_rad: 0.02,
            window_m: 1.0,
            step_m: 0.1,
            window_rad: 0.05,
            step_rad: 0.0125,
            max_scored_points: 120,
            inlier_m: 0.1,
            min_age: 40,
            min_score_ratio: 0.12,
            min_gain: 2.0,
            max_ambiguity: 0.9,
            max_across_spread_m: 0.1,
            max_turn_spread_rad: 0.026,
        }
    }
}

/// What a search saw, in soft inlier counts: the winner, the guess and the best distinct rival.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchScores {
    pub best: f32,
    pub at_guess: f32,
    /// Standard deviation, across their main axis, of the poses scoring nearly as well as the
    /// winner, m (not computed, 0, when the winner already failed the other tests).
    pub across_spread_m: f32,
}

/// Why a search moved nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Declined {
    /// Too early in the run for any wall to be old, or an empty scan or a zero step.
    NothingToSearch,
    /// No pose stood out; the scores say which test failed.
    NoClearWinner(SearchScores),
}

/// The pose at which `points` (scan frame) line up with the old walls of `map` near `guess`,
/// if one stands out; `now` is the current stamp.
///
/// Only the old walls score, so a pose that puts more of the scan over walls mapped long ago
/// scores higher merely for that. Driving down a corridor whose near end was mapped long ago,
/// the best poses lie back along the corridor, and a search that took its best pose would jump
/// there: in the simulator's office with a 30 m lidar, 1 m jumps along the corridor at every
/// search, 8.8 m of mean error where the map without the search has 1 cm. There the score is a
/// slope that runs
/// off one edge of the window, not a peak. So a winner on the window's edge is searched again
/// from a window centred on it (a real peak may lie just beyond), and the answer counts only if
/// the poses scoring nearly as well as the winner reach no edge of that window without also
/// reaching the opposite one: a peak inside, or a corridor's plateau running right through.
pub fn relocalize(
    map: &LineMap,
    points: &[Vec2],
    guess: Pose2,
    now: u32,
    config: &RelocalizeConfig,
) -> Result<Pose2, Declined> {
    if points.is_empty() || !(config.step_m > 0.0 && config.step_rad > 0.0) {
        return Err(Declined::NothingToSearch);
    }
    let old_before = now
        .checked_sub(config.min_age)
        .ok_or(Declined::NothingToSearch)?;
    let search = Search {
        map,
        points,
        old_before: old_before as f32,
        config,
    };
    let at_guess = search.score(guess);
    let mut peak = search.best_in_window(guess);
    if peak.on_edge {
        // The new window holds the old peak, so its best scores at least as well.
        peak = search.best_in_window(peak.pose);
    }
    let mut scores = SearchScores {
        best: peak.score,
        at_guess,
        across_spread_m: 0.0,
    };
    if peak.score < config.min_score_ratio * search.scored() as f32
        || peak.score < config.min_gain * at_guess
    {
        return Err(Declined::NoClearWinner(scores));
    }
    let spread = search.near_best(peak, guess);
    scores.across_spread_m = spread.across_m;
    if spread.across_m <= config.max_across_spread_m
        && spread.max_turn_rad <= config.max_turn_spread_rad
        && !spread.edges.is_slope()
    {
        Ok(spread.nearest)
    } else {
        Err(Declined::NoClearWinner(scores))
    }
}

/// One search's inputs: the scan, the map and which of its cells count as old.
struct Search<'a, 'm> {
    map: &'a LineMap<'m>,
    points: &'a [Vec2],
    old_before: f32,
    config: &'a RelocalizeConfig,
}

/// The best pose of a window, and whether it lies on the window's edge.
#[derive(Clone, Copy)]
struct Peak {
    pose: Pose2,
    score: f32,
    /// The window the peak was found in.
    centre: Pose2,
    on_edge: bool,
}

/// Which edges of a search window (-x, +x, -y, +y: bits 0 to 3) something reaches.
#[derive(Clone, Copy, Default)]
struct Edges(u8);

impl Edges {
    /// An edge reached without its opposite: the score still rises off the window there.
    fn is_slope(self) -> bool {
        let (minus, plus) = (self.0 & 0b0101, (self.0 >> 1) & 0b0101);
        minus != plus
    }
}

/// How the poses scoring nearly as well as a peak spread.
struct Spread {
    across_m: f32,
    max_turn_rad: f32,
    /// The window's edges they reach.
    edges: Edges,
    /// Of them, the one nearest the guess.
    nearest: Pose2,
}

impl Search<'_, '_> {
    /// Every k-th point of a denser scan: the search visits thousands of poses, and a hundred-odd
    /// points already tell walls apart.
    fn stride(&self) -> usize {
        self.points
            .len()
            .div_ceil(self.config.max_scored_points.max(1))
    }

    fn scored(&self) -> usize {
        self.points.len().div_ceil(self.stride())
    }

    /// The soft count of scored points on old walls at `pose`.
    fn score(&self, pose: Pose2) -> f32 {
        self.score_rotated(
            (libm::sinf(pose.theta), libm::cosf(pose.theta)),
            pose.x,
            pose.y,
        )
    }

    /// [`Self::score`] for points rotated by a heading whose sine and cosine are given.
    fn score_rotated(&self, rotation: (f32, f32), x: f32, y: f32) -> f32 {
        let (sin, cos) = rotation;
        self.points
            .iter()
            .step_by(self.stride())
            .map(|p| {
                let w = Vec2::new(cos * p.x - sin * p.y + x, sin * p.x + cos * p.y + y);
                self.map
                    .lines_near(w)
                    .into_iter()
                    .flatten()
                    .filter(|l| l.mean_stamp <= self.old_before)
                    .map(|l| 1.0 - (w - l.mean).dot(l.normal).abs() / self.config.inlier_m)
                    .fold(0.0f32, f32::max)
            })
            .sum()
    }

    /// Visits every pose of the window centred on `centre` with its score and the window's
    /// translation edges it lies on.
    fn window(&self, centre: Pose2, visit: &mut dyn FnMut(Pose2, f32, Edges)) {
        let c = self.config;
        let n = libm::roundf(c.window_m / c.step_m) as i32;
        let m = libm::roundf(c.window_rad / c.step_rad) as i32;
        for k in -m..=m {
            let theta = centre.theta + k as f32 * c.step_rad;
            let rotation = (libm::sinf(theta), libm::cosf(theta));
            for i in -n..=n {
                for j in -n..=n {
                    let (x, y) = (
                        centre.x + i as f32 * c.step_m,
                        centre.y + j as f32 * c.step_m,
                    );
                    let edge = Edges(
                        u8::from(i == -n)
                            | u8::from(i == n) << 1
                            | u8::from(j == -n) << 2
                            | u8::from(j == n) << 3,
                    );
                    visit(
                        Pose2::new(x, y, theta),
                        self.score_rotated(rotation, x, y),
                        edge,
                    );
                }
            }
        }
    }

    fn best_in_window(&self, centre: Pose2) -> Peak {
        let mut peak = Peak {
            pose: centre,
            score: f32::MIN,
            centre,
            on_edge: false,
        };
        self.window(centre, &mut |pose, score, edge| {
            if score > peak.score {
                (peak.pose, peak.score, peak.on_edge) = (pose, score, edge.0 != 0);
            }
        });
        peak
    }

    /// Every pose of the peak's window scoring nearly as well as the peak: along a corridor
    /// they form a line, which still fixes heading and the position across it; spread both
    /// ways they mean the scan fits several places and nothing can be trusted.
    fn near_best(&self, peak: Peak, guess: Pose2) -> Spread {
        let near_best = self.config.max_ambiguity * peak.score;
        let (mut count, mut sx, mut sy, mut sxx, mut sxy, mut syy) =
            (0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut max_turn_rad = 0.0f32;
        let mut nearest = (f32::MAX, peak.pose);
        let mut edges = Edges::default();
        self.window(peak.centre, &mut |pose, score, edge| {
            if score < near_best {
                return;
            }
            let (dx, dy) = (pose.x - peak.pose.x, pose.y - peak.pose.y);
            count += 1.0;
            (sx, sy) = (sx + dx, sy + dy);
            (sxx, sxy, syy) = (sxx + dx * dx, sxy + dx * dy, syy + dy * dy);
            max_turn_rad = max_turn_rad.max(normalize_angle(pose.theta - peak.pose.theta).abs());
            edges.0 |= edge.0;
            let d = guess.distance_to(pose).0;
            if d < nearest.0 {
                nearest = (d, pose);
            }
        });
        let (mx, my) = (sx / count, sy / count);
        let (_, across, _) = sym2_eigen(
            sxx / count - mx * mx,
            sxy / count - mx * my,
            syy / count - my * my,
        );
        Spread {
            across_m: libm::sqrtf(across.max(0.0)),
            max_turn_rad,
            edges,
            nearest: nearest.1,
        }
    }
}
