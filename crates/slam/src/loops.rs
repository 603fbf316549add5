//! Loop closure: which old keyframes a new one may see again, and the checks a match must pass
//! before it may pull the map together.
//!
//! Candidates come from frozen submaps only (the rolling local map already ties a keyframe to
//! its recent past) and lie near the new keyframe by the graph's current estimate, within a
//! radius that grows with the distance travelled since, because that is how far the estimate
//! can have drifted, whichever way the vehicle faced then: a corridor retraced in the opposite
//! direction is a revisit too. Each is placed by a correlative search against the candidate and
//! its neighbours, then verified by the ICL matcher against those same keyframes rendered as
//! one scan seen from there: it must converge, pair most points tightly, and move the coarse
//! answer no further than a few cells. What passes is still only a proposal: the pose graph's robust kernel has the
//! last word, so one false match cannot bend the map.

use crate::config::LoopConfig;
use crate::correlative::{Found, LookupGrid, Window};
use crate::keyframe::Keyframe;
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::matching::{MatchResult, MatchStatus, ScanMatcher};
use plumbline_core::scan::{Beam, Scan};

/// A verified loop: the pose of keyframe `to` in the frame of keyframe `from`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopEdge {
    pub from: usize,
    pub to: usize,
    pub measurement: Pose2,
    pub result: MatchResult,
    /// The coarse search's mean likelihood at its answer.
    pub score: f32,
}

/// Why a candidate was turned down.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    /// No pose in the search window fits well enough.
    NoCoarseFit,
    MatchFailed,
    NotConverged,
    FewInliers,
    LargeResidual,
    TooFarFromGuess,
    /// The scans constrain one direction too weakly (a corridor).
    Degenerate,
    /// Another pose in the window, away from the best, fits almost as well (alike rooms).
    Ambiguous,
}

pub struct LoopCloser<const N: usize> {
    config: LoopConfig,
    matcher: Box<ScanMatcher<N>>,
    reference: Box<Scan<N>>,
    current: Box<Scan<N>>,
}

impl<const N: usize> LoopCloser<N> {
    pub fn new(config: LoopConfig) -> Self {
        Self {
            config,
            matcher: Box::new(ScanMatcher::new(config.matcher)),
            reference: Box::default(),
            current: Box::default(),
        }
    }

    /// Old keyframes worth verifying against keyframe `new`, nearest first: at most one per
    /// submap (its keyframe nearest the new one) and at most `max_candidates` in all.
    pub fn candidates(&self, keyframes: &[Keyframe], poses: &[Pose2], new: usize) -> Vec<usize> {
        let cfg = &self.config;
        let Some(newest) = keyframes.get(new) else {
            return Vec::new();
        };
        let last_submap = newest.submap.saturating_sub(cfg.min_submap_gap);
        if newest.submap < cfg.min_submap_gap {
            return Vec::new();
        }
        let here = poses[new];
        let mut best_per_submap: Vec<(f32, usize)> = Vec::new();
        for (j, kf) in keyframes[..new].iter().enumerate() {
            if kf.submap > last_submap {
                break;
            }
            let dist = poses[j].distance_to(here).0;
            let reach = cfg.search_radius_m + cfg.drift_per_m * (newest.path_m - kf.path_m);
            if dist > reach || kf.predicted || !kf.has_scan() {
                continue;
            }
            match best_per_submap.last_mut() {
                Some(last) if keyframes[last.1].submap == kf.submap => {
                    if dist < last.0 {
                        *last = (dist, j);
                    }
                }
                _ => best_per_submap.push((dist, j)),
            }
        }
        best_per_submap.sort_by(|a, b| a.0.total_cmp(&b.0));
        best_per_submap
            .into_iter()
            .take(cfg.max_candidates)
            .map(|(_, j)| j)
            .collect()
    }

    /// The pose of keyframe `to` in `from`'s frame by matching their scans directly, from
    /// `guess`; `None` unless the match converges, pairs most points tightly and fixes both
    /// directions of translation (the same checks as a loop's).
    pub fn match_pair(
        &mut self,
        keyframes: &[Keyframe],
        from: usize,
        to: usize,
        guess: Pose2,
    ) -> Option<Pose2> {
        let cfg = &self.config;
        keyframes[from].to_scan(&mut self.reference);
        keyframes[to].to_scan(&mut self.current);
        self.matcher.set_reference(&self.reference).ok()?;
        let result = self.matcher.match_scan(&self.current, guess).ok()?;
        let q = &result.quality;
        let good = q.status == MatchStatus::Converged
            && q.inlier_ratio >= cfg.min_inlier_ratio
            && q.rms_residual_m <= cfg.max_rms_m
            && q.degenerate_direction.is_none()
            && q.conditioning >= cfg.min_conditioning;
        good.then_some(result.motion)
    }

    /// How many of its candidates keyframe `new` may verify: one per `candidate_interval_s`
    /// since the previous keyframe, at least one, at most `max_candidates`.
    pub fn budget(&self, keyframes: &[Keyframe], new: usize) -> usize {
        let cfg = &self.config;
        let since_s = match (new.checked_sub(1), keyframes.get(new)) {
            (Some(previous), Some(newest)) => newest.stamp_s - keyframes[previous].stamp_s,
            _ => 0.0,
        };
        let earned = (since_s / cfg.candidate_interval_s as f64).floor();
        (earned.max(1.0) as usize).min(cfg.max_candidates.max(1))
    }

    /// Matches keyframe `to` against keyframe `from`, starting from the graph's relative pose.
    pub fn verify(
        &mut self,
        keyframes: &[Keyframe],
        poses: &[Pose2],
        from: usize,
        to: usize,
        guess: Pose2,
    ) -> Result<LoopEdge, Rejection> {
        let cfg = &self.config;
        let coarse = self.coarse_search(keyframes, poses, from, to, guess)?;
        // The reference is the old place as seen from where the coarse search put the new
        // keyframe, rendered from the candidate and its neighbours: a keyframe passing the old
        // one in the opposite direction saw the walls the new one sees now from their other
        // end, which a single old scan through a 180° lidar does not hold.
        let viewpoint = coarse.found.pose;
        render_view(&coarse.reference, viewpoint, &mut self.reference);
        keyframes[to].to_scan(&mut self.current);
        self.matcher
            .set_reference(&self.reference)
            .map_err(|_| Rejection::MatchFailed)?;
        let mut result = self
            .matcher
            .match_scan(&self.current, Pose2::IDENTITY)
            .map_err(|_| Rejection::MatchFailed)?;
        result.motion = viewpoint.compose(result.motion);
        let q = &result.quality;
        if q.status != MatchStatus::Converged {
            return Err(Rejection::NotConverged);
        }
        if q.inlier_ratio < cfg.min_inlier_ratio {
            return Err(Rejection::FewInliers);
        }
        if q.rms_residual_m > cfg.max_rms_m {
            return Err(Rejection::LargeResidual);
        }
        // Along a corridor the scans do not fix the position: such a match would pin the
        // loop to wherever the search happened to stop.
        if q.degenerate_direction.is_some() || q.conditioning < cfg.min_conditioning {
            return Err(Rejection::Degenerate);
        }
        let (shift, turn) = coarse.found.pose.distance_to(result.motion);
        if shift > cfg.max_correction_m || turn > cfg.max_correction_rad {
            return Err(Rejection::TooFarFromGuess);
        }
        // Last, being the dearest check: does the scan fit another place almost as well?
        let rival = coarse.grid.rival(
            &coarse.current,
            coarse.guess,
            coarse.window,
            &coarse.found,
            cfg.rival,
            &cfg.correlative,
        );
        if rival.is_some() {
            return Err(Rejection::Ambiguous);
        }
        Ok(LoopEdge {
            from,
            to,
            measurement: result.motion,
            result,
            score: coarse.found.score,
        })
    }

    /// The best pose of keyframe `to` in `from`'s frame within the window around `guess`, against
    /// `from` and its neighbours placed by the graph.
    fn coarse_search(
        &self,
        keyframes: &[Keyframe],
        poses: &[Pose2],
        from: usize,
        to: usize,
        guess: Pose2,
    ) -> Result<Coarse, Rejection> {
        let cfg = &self.config;
        // Passing the other way, the new keyframe faces what the old path saw on its way to
        // and from the candidate, held by keyframes farther from it.
        let neighbours = if guess.theta.abs() > core::f32::consts::FRAC_PI_2 {
            cfg.reference_neighbours_opposite
        } else {
            cfg.reference_neighbours
        };
        let first = from.saturating_sub(neighbours);
        let last = (from + neighbours).min(to.saturating_sub(1));
        let mut reference: Vec<Vec2> = Vec::new();
        for k in (first..=last).filter(|&k| keyframes[k].has_scan()) {
            let into_from = poses[from].between(poses[k]).placement();
            reference.extend(keyframes[k].points().map(|p| into_from.transform(p)));
        }
        // Only points the search scores (within its range) and reference points they can land
        // on matter: the grid covers that extent at the guess, grown by the window, not every
        // far wall either scan saw down a corridor.
        let range = cfg.correlative.max_range_m;
        let current: Vec<Vec2> = keyframes[to]
            .points()
            .filter(|p| p.norm() <= range)
            .collect();
        let at_guess = guess.placement();
        let (lo, hi) = bounds(current.iter().map(|&p| at_guess.transform(p)));
        let travelled = (keyframes[to].path_m - keyframes[from].path_m).abs();
        let window = Window {
            translation_m: (cfg.window_floor_m + cfg.drift_per_m * travelled).min(cfg.window_max_m),
            heading_rad: (cfg.window_floor_rad + cfg.window_rad_per_m * travelled)
                .min(cfg.window_max_rad),
        };
        let reach = window.translation_m
            + reach_m(&current).min(cfg.correlative.max_range_m) * window.heading_rad.sin()
            + 0.5;
        reference.retain(|p| {
            p.x >= lo.x - reach && p.x <= hi.x + reach && p.y >= lo.y - reach && p.y <= hi.y + reach
        });
        let grid = LookupGrid::new(&reference, 0.5, &cfg.correlative, 5);
        let found = grid
            .search(&current, guess, window, cfg.min_score, &cfg.correlative)
            .ok_or(Rejection::NoCoarseFit)?;
        Ok(Coarse {
            reference,
            grid,
            current,
            guess,
            window,
            found,
        })
    }
}

/// A coarse search's answer, with what a rival search needs to repeat it.
struct Coarse {
    /// The reference points, in the frame of keyframe `from`.
    reference: Vec<Vec2>,
    grid: LookupGrid,
    current: Vec<Vec2>,
    guess: Pose2,
    window: Window,
    found: Found,
}

/// Angular bins of a rendered view: half a degree, finer than the beam spacing of the 180°
/// lidars of the benchmark logs, so a view keeps their detail.
const VIEW_BINS: usize = 720;

/// Fills `view` with the `points` (in some frame) as a full-circle scan seen from `viewpoint`
/// (in that frame): the nearest point in each angular bin, at its own bearing, so walls hide
/// what lies behind them as they would for a lidar standing there.
fn render_view<const N: usize>(points: &[Vec2], viewpoint: Pose2, view: &mut Scan<N>) {
    let bins = VIEW_BINS.min(N);
    let width = core::f32::consts::TAU / bins as f32;
    let mut nearest: Vec<Option<Beam>> = vec![None; bins];
    let into_view = viewpoint.inverse().placement();
    for &p in points {
        let local = into_view.transform(p);
        let (range, bearing) = (local.norm(), local.y.atan2(local.x));
        if !(range > 0.0 && range.is_finite()) {
            continue;
        }
        let bin = (((bearing + core::f32::consts::PI) / width) as usize).min(bins - 1);
        if nearest[bin].is_none_or(|b| range < b.range_m) {
            nearest[bin] = Some(Beam::new(bearing, range));
        }
    }
    view.clear(0.0);
    for beam in nearest.into_iter().flatten() {
        // Cannot fail: at most `bins <= N` beams go into an empty scan of N.
        let _ = view.push(beam);
    }
}

/// Lower-left and upper-right corners of the points' bounding box.
fn bounds(points: impl Iterator<Item = Vec2>) -> (Vec2, Vec2) {
    points.fold(
        (Vec2::new(f32::MAX, f32::MAX), Vec2::new(f32::MIN, f32::MIN)),
        |(lo, hi), p| {
            (
                Vec2::new(lo.x.min(p.x), lo.y.min(p.y)),
                Vec2::new(hi.x.max(p.x), hi.y.max(p.y)),
            )
        },
    )
}

/// Range of the farthest point, m.
fn reach_m(points: &[Vec2]) -> f32 {
    points.iter().map(|p| p.norm()).fold(0.0, f32::max)
}
