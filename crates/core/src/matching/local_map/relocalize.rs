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
    // Scores a translation for points already rotated by the candidate heading.
    let stride = points.len().div_ceil(config.max_scored_points.max(1));
    let scored = points.len().div_ceil(stride);
    let score = |rotation: (f32, f32), x: f32, y: f32| -> f32 {
        let (sin, cos) = rotation;
        points
            .iter()
            .step_by(stride)
            .map(|p| {
                let w = Vec2::new(cos * p.x - sin * p.y + x, sin * p.x + cos * p.y + y);
                map.lines_near(w)
                    .into_iter()
                    .flatten()
                    .filter(|l| l.mean_stamp <= old_before as f32)
                    .map(|l| 1.0 - (w - l.mean).dot(l.normal).abs() / config.inlier_m)
                    .fold(0.0f32, f32::max)
            })
            .sum()
    };
    let n = libm::roundf(config.window_m / config.step_m) as i32;
    let m = libm::roundf(config.window_rad / config.step_rad) as i32;
    let window = |visit: &mut dyn FnMut(Pose2, f32)| {
        for k in -m..=m {
            let theta = guess.theta + k as f32 * config.step_rad;
            let rotation = (libm::sinf(theta), libm::cosf(theta));
            for i in -n..=n {
                for j in -n..=n {
                    let (x, y) = (
                        guess.x + i as f32 * config.step_m,
                        guess.y + j as f32 * config.step_m,
                    );
                    visit(Pose2::new(x, y, theta), score(rotation, x, y));
                }
            }
        }
    };
    let at_guess = score(
        (libm::sinf(guess.theta), libm::cosf(guess.theta)),
        guess.x,
        guess.y,
    );
    let mut best = (f32::MIN, guess);
    window(&mut |pose, s| {
        if s > best.0 {
            best = (s, pose);
        }
    });
    let mut scores = SearchScores {
        best: best.0,
        at_guess,
        across_spread_m: 0.0,
    };
    if best.0 < config.min_score_ratio * scored as f32 || best.0 < config.min_gain * at_guess {
        return Err(Declined::NoClearWinner(scores));
    }
    // Every pose scoring nearly as well as the winner: along a corridor they form a line, which
    // still fixes heading and the position across it; spread both ways they mean the scan fits
    // several places and nothing can be trusted. Of the set, the pose nearest the guess is taken.
    let near_best = config.max_ambiguity * best.0;
    let (mut count, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut max_turn = 0.0f32;
    let mut nearest = (f32::MAX, best.1);
    window(&mut |pose, s| {
        if s < near_best {
            return;
        }
        let (dx, dy) = (pose.x - best.1.x, pose.y - best.1.y);
        count += 1.0;
        (sx, sy) = (sx + dx, sy + dy);
        (sxx, sxy, syy) = (sxx + dx * dx, sxy + dx * dy, syy + dy * dy);
        max_turn = max_turn.max(normalize_angle(pose.theta - best.1.theta).abs());
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
    scores.across_spread_m = libm::sqrtf(across.max(0.0));
    if scores.across_spread_m <= config.max_across_spread_m
        && max_turn <= config.max_turn_spread_rad
    {
        Ok(nearest.1)
    } else {
        Err(Declined::NoClearWinner(scores))
    }
}
