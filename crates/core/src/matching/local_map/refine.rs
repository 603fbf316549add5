//! Scan-to-map refinement: Gauss-Newton on point-to-line distances against the local map's cell
//! lines, pulled towards the scan matcher's pose by its own information.
//!
//! Scan-to-keyframe matching leaves a small heading error at every keyframe, and those errors
//! add up into the drift that dominates long-range accuracy. Aligning each new keyframe with
//! the map made of all the keyframes before it ties its heading to walls seen many metres and
//! many seconds ago, which is what keeps the drift from growing while the vehicle stays in
//! mapped space.

use super::cells::LineMap;
use crate::geom::{normalize_angle, Pose2, Vec2};
use crate::matching::linalg::Sym3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineConfig {
    pub max_iterations: u8,
    /// Points farther than this from every nearby map line take no part, m.
    pub gate_m: f32,
    /// Cauchy scale of the robust weight, m.
    pub robust_scale_m: f32,
    /// Range noise assumed for the scan's own points, m (added to the cell's spread).
    pub point_sigma_m: f32,
    /// Fewest points that must find a map line for the result to count.
    pub min_matched: u16,
    /// …and at least this fraction of the scan's points.
    pub min_matched_ratio: f32,
    /// Stop when a step moves less than this, m and rad.
    pub converged_m: f32,
    pub converged_rad: f32,
    /// A result farther than this from the guess is refused as a wrong alignment, m and rad.
    pub max_shift_m: f32,
    pub max_turn_rad: f32,
    /// Least over most translational information of the map below which the weak direction is
    /// held at the guess (the scan matcher's degenerate-direction test uses the same ratio).
    pub min_conditioning: f32,
    /// Scale on the scan matcher's information when its pose is the prior. Its covariance
    /// assumes independent point errors and is far too confident; at 1 the map could barely
    /// move a keyframe, at 0.001 and below the map alone decides and wrong alignments creep in
    /// (measured on the Intel and MIT logs, BENCHMARKS.md).
    pub matcher_weight: f32,
    /// Largest squared Mahalanobis distance from the guess to the refined pose, under the scan
    /// matcher's own covariance times the age of the walls met ([`correction_is_plausible`]).
    /// Far above a chi-square quantile because that covariance is about a hundred times too
    /// confident (see `matcher_weight`); 100-500 all served on the logs (BENCHMARKS.md).
    pub max_correction_d2: f32,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self {
            max_iterations: 12,
            gate_m: 0.2,
            robust_scale_m: 0.05,
            point_sigma_m: 0.02,
            min_matched: 40,
            min_matched_ratio: 0.3,
            converged_m: 1e-4,
            converged_rad: 1e-4,
            max_shift_m: 0.3,
            max_turn_rad: 0.1,
            min_conditioning: 0.02,
            matcher_weight: 0.02,
            max_correction_d2: 300.0,
        }
    }
}

/// A pose the map agrees with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refined {
    pub pose: Pose2,
    /// Points that found a map line in the last pass.
    pub matched: u16,
    pub iterations: u8,
}

/// Why the map could not be used for this scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefineRefusal {
    /// Too few points lie on mapped walls (new space, or the guess is far off).
    TooFewMatched { matched: u16, needed: u16 },
    /// The solution left the trust region around the guess or stopped being finite.
    Diverged,
    /// The map would move the pose farther than the scan matcher can have drifted since the
    /// walls it met were mapped (squared Mahalanobis distance `d2`).
    Implausible { d2: f32 },
}

/// Aligns `points` (scan frame) with `map`, starting from `guess` (world frame).
/// `prior_information` weighs the guess, in (x, y, theta) world frame, 1/m² and 1/rad²; it is
/// what holds the pose where the map has nothing to say, such as along a corridor.
pub fn refine(
    map: &LineMap,
    points: &[Vec2],
    guess: Pose2,
    prior_information: Sym3,
    config: &RefineConfig,
) -> Result<Refined, RefineRefusal> {
    let needed = config
        .min_matched
        .max((config.min_matched_ratio * points.len() as f32) as u16);
    let mut pose = guess;
    let mut matched = 0u16;
    let mut iterations = 0u8;
    while iterations < config.max_iterations {
        iterations += 1;
        let (mut h, mut g) = (Sym3::default(), [0.0f32; 3]);
        matched = 0;
        let (s, c) = (libm::sinf(pose.theta), libm::cosf(pose.theta));
        for &p in points {
            let rotated = Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y);
            let w = rotated + pose.translation();
            let Some((r, line)) = nearest_line(map, w, config.gate_m) else {
                continue;
            };
            matched += 1;
            let sigma2 = config.point_sigma_m * config.point_sigma_m + line.across_variance_m2;
            let u = r / config.robust_scale_m;
            let weight = 1.0 / (sigma2 * (1.0 + u * u));
            let j = [
                line.normal.x,
                line.normal.y,
                line.normal.dot(rotated.perp()),
            ];
            h.add_outer(j, weight);
            for k in 0..3 {
                g[k] += weight * r * j[k];
            }
        }
        if matched < needed {
            return Err(RefineRefusal::TooFewMatched { matched, needed });
        }
        let prior = prior_information.plus(&pin_unobserved(&h, config.min_conditioning));
        let offset = [
            pose.x - guess.x,
            pose.y - guess.y,
            normalize_angle(pose.theta - guess.theta),
        ];
        let pulled = prior.mul(offset);
        let h = h.plus(&prior);
        let rhs = [
            -(g[0] + pulled[0]),
            -(g[1] + pulled[1]),
            -(g[2] + pulled[2]),
        ];
        let step = h.inverse().ok_or(RefineRefusal::Diverged)?.mul(rhs);
        pose = Pose2::new(pose.x + step[0], pose.y + step[1], pose.theta + step[2]);
        let (shift, turn) = guess.distance_to(pose);
        if !pose.is_finite() || shift > config.max_shift_m || turn > config.max_turn_rad {
            return Err(RefineRefusal::Diverged);
        }
        if libm::hypotf(step[0], step[1]) < config.converged_m
            && step[2].abs() < config.converged_rad
        {
            break;
        }
    }
    Ok(Refined {
        pose,
        matched,
        iterations,
    })
}

/// Where the map's walls leave a translation direction nearly free (a corridor's axis), noisy
/// cell normals would still pull along it; a prior as strong as the best-constrained direction
/// holds the guess there instead, the way the scan matcher's own degenerate direction is held.
fn pin_unobserved(map_information: &Sym3, min_conditioning: f32) -> Sym3 {
    match map_information.weak_translation(min_conditioning) {
        Some((hi, v)) => Sym3 {
            xx: hi * v.x * v.x,
            xy: hi * v.x * v.y,
            yy: hi * v.y * v.y,
            ..Sym3::default()
        },
        None => Sym3::default(),
    }
}

/// The signed distance from `w` to the nearest map line around it, within `gate_m`.
fn nearest_line(map: &LineMap, w: Vec2, gate_m: f32) -> Option<(f32, super::cells::CellLine)> {
    map.lines_near(w)
        .into_iter()
        .flatten()
        .map(|line| ((w - line.mean).dot(line.normal), line))
        .filter(|(r, _)| r.abs() <= gate_m)
        .min_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))
}

/// How many keyframes ago, on average, the walls that `points` meet at `pose` were mapped:
/// `now` minus the mean stamp of the lines they find within `gate_m`, at least one keyframe.
/// `None` when no point meets a wall.
pub fn map_age(map: &LineMap, points: &[Vec2], pose: Pose2, now: u32, gate_m: f32) -> Option<f32> {
    let (mut stamp_sum, mut met) = (0.0f32, 0u32);
    for &p in points {
        if let Some((_, line)) = nearest_line(map, pose.transform(p), gate_m) {
            stamp_sum += line.mean_stamp;
            met += 1;
        }
    }
    (met > 0).then(|| (now as f32 - stamp_sum / met as f32).max(1.0))
}

/// Checks the map's correction from `guess` to `refined` against the drift the scan matcher can
/// have made since the walls were mapped.
///
/// Why: each keyframe's match adds an error of about the matcher's covariance, so relative to
/// walls mapped `age_keyframes` ago the guess is off by a random walk of covariance `age` times
/// that. Against walls mapped a few keyframes ago the map knows little more than the matcher,
/// and a large correction there comes from clutter in the cells, not from drift: on MIT's
/// cluttered start such corrections of up to 0.06 rad turned the trajectory by 0.09 rad within
/// a minute (BENCHMARKS.md). `matcher_information` is the inverse of that covariance in the
/// world frame. Returns the squared distance when it exceeds `max_d2`.
pub fn correction_is_plausible(
    guess: Pose2,
    refined: Pose2,
    matcher_information: &Sym3,
    age_keyframes: f32,
    max_d2: f32,
) -> Result<(), RefineRefusal> {
    let d = [
        refined.x - guess.x,
        refined.y - guess.y,
        normalize_angle(refined.theta - guess.theta),
    ];
    let m = matcher_information.mul(d);
    let d2 = (d[0] * m[0] + d[1] * m[1] + d[2] * m[2]) / age_keyframes.max(1.0);
    if d2 <= max_d2 {
        Ok(())
    } else {
        Err(RefineRefusal::Implausible { d2 })
    }
}
