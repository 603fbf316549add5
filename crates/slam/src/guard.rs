//! A cheap check of the tracker's motion guess, and a wide search when it fails.
//!
//! The tracker starts each match from the last motion repeated (or the caller's prior). After a
//! sharp turn, a dropped scan, or in a log thinned to one scan in eight, that guess can be far
//! outside the basin the matcher converges from, and its own recovery searches only a small box.
//! So before every match the guess is scored against a likelihood grid of the current keyframe
//! (about a hundred look-ups); only when it fits badly does a branch-and-bound correlative
//! search over a wide window (Olson 2009) run and hand the tracker a better guess.
//!
//! A 180° lidar that turned most of a half turn between two scans shares only a sliver of its
//! view with the keyframe: no pose fits that keyframe well, or several far apart fit it about
//! equally well. The vehicle has usually seen the rest of the place on the way there, so the
//! search is also made against the last keyframes together: the local map. Its answer is taken
//! when the keyframe has none, or when it is one of the keyframe's own near-equal peaks and the
//! local map fits it much better than the keyframe's winner. It does not replace the keyframe's
//! search: along a corridor the older keyframes carry the tracker's drift, and a scan fits them
//! in more places than it fits the keyframe it is matched against.

use crate::config::GuardConfig;
use crate::correlative::{CorrelativeConfig, Found, LookupGrid, MotionPrior, Window};
use crate::keyframe::Keyframe;
use plumbline_core::geom::{Pose2, Vec2};

/// What the check did for one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guarded {
    /// The guess fit (or there was nothing to check against).
    GuessKept,
    /// The guess fit badly and the search found a better one.
    Searched { score: f32 },
    /// The guess fit badly and the last keyframes together (the local map) placed the scan:
    /// the keyframe alone held nothing better, or held several poses about as good and the
    /// local map fit one of them much better than the keyframe's winner.
    SearchedMap { score: f32 },
    /// The guess fit badly and the search found nothing better.
    NothingBetter,
}

pub struct GuessGuard {
    config: GuardConfig,
    /// The keyframe the grids were built for, a one-level grid for checks and a pyramid for
    /// searches (built on the first search).
    keyframe: Option<usize>,
    check: Option<LookupGrid>,
    search: Option<LookupGrid>,
    /// The last keyframes (the current one last), for the search against the local map.
    recent: std::collections::VecDeque<Keyframe>,
}

impl GuessGuard {
    pub fn new(config: GuardConfig) -> Self {
        Self {
            config,
            keyframe: None,
            check: None,
            search: None,
            recent: std::collections::VecDeque::new(),
        }
    }

    /// The guess for a scan whose points are `points`, if the tracker's own should be replaced:
    /// `guess` is the scan's pose in the frame of keyframe `index` that the tracker will try,
    /// made by repeating the last motion over `gap_s` since the last scan that matched.
    pub fn check(
        &mut self,
        keyframe: &Keyframe,
        index: usize,
        points: &[Vec2],
        guess: Pose2,
        gap_s: f32,
    ) -> (Guarded, Option<Pose2>) {
        let cfg = &self.config;
        if !cfg.enabled || points.is_empty() {
            return (Guarded::GuessKept, None);
        }
        // Scored points lie within `max_range_m` of the scan, and the scan within the largest
        // step plus the window of the keyframe: farther reference points cannot be reached and
        // would only grow the grid. Nearer ones must all be there, or a scan that moved far
        // would find its farthest points on empty cells and fit better short of where it is.
        let reach = cfg.correlative.max_range_m + cfg.max_step_m;
        let reference =
            || -> Vec<Vec2> { keyframe.points().filter(|p| p.norm() <= reach).collect() };
        if self.keyframe != Some(index) {
            let reference = reference();
            self.check = Some(LookupGrid::new(&reference, 0.0, &cfg.correlative, 1));
            self.search = None;
            self.keyframe = Some(index);
            self.recent.push_back(keyframe.clone());
            while self.recent.len() > cfg.map_keyframes.max(1) {
                self.recent.pop_front();
            }
        }
        let Some(check) = &self.check else {
            return (Guarded::GuessKept, None);
        };
        let guess_score = check.score_pose(points, guess, &cfg.correlative);
        if guess_score >= cfg.min_guess_score {
            return (Guarded::GuessKept, None);
        }
        let search = self
            .search
            .get_or_insert_with(|| LookupGrid::new(&reference(), 0.5, &cfg.correlative, 5));
        // How far the motion may have strayed from the repeated one over the gap: the search
        // reaches three times that (bounded work), and poses are penalised by how unlikely it is.
        let gap_s = if gap_s.is_finite() {
            gap_s.max(0.0)
        } else {
            0.0
        };
        let spread = |floor: f32, accel: f32| floor + 0.5 * accel * gap_s * gap_s;
        let sigma_m = spread(cfg.sigma_floor_m, cfg.accel_m_s2);
        let sigma_rad = spread(cfg.sigma_floor_rad, cfg.turn_accel_rad_s2);
        let window = Window {
            translation_m: (3.0 * sigma_m).clamp(cfg.window_m, cfg.max_step_m),
            heading_rad: (3.0 * sigma_rad).clamp(cfg.window_rad, std::f32::consts::PI),
        };
        let prior = MotionPrior {
            per_m2: cfg.prior_weight / (sigma_m * sigma_m),
            per_rad2: cfg.prior_weight / (sigma_rad * sigma_rad),
        };
        // When nothing fits there, the motion was not what the gap suggests (a log with
        // stamps that do not tell, a spin in place): the widest window, without the penalty.
        let widest = Window {
            translation_m: cfg.max_step_m,
            heading_rad: std::f32::consts::PI,
        };
        let floor = (guess_score * cfg.min_gain).max(cfg.min_found_score);
        let passes = [(window, prior), (widest, MotionPrior::default())];
        // The penalised winner is the answer; its own fit decides whether it is good enough.
        let best_in = |grid: &LookupGrid| {
            passes.into_iter().find_map(|(window, prior)| {
                grid.search_near(points, guess, window, prior, 0.0, &cfg.correlative)
                    .filter(|found| found.score >= floor)
            })
        };
        let from_keyframe = best_in(search);
        if cfg.map_keyframes <= 1 {
            return from_keyframe.map_or((Guarded::NothingBetter, None), |found| {
                (Guarded::Searched { score: found.score }, Some(found.pose))
            });
        }
        let local = local_map(&self.recent, keyframe, reach, &cfg.correlative);
        let from_map = best_in(&local);
        match (from_keyframe, from_map) {
            // The keyframe's winner, unless the local map settles what the keyframe cannot.
            (Some(winner), Some(found))
                if found.score - local.score_pose(points, winner.pose, &cfg.correlative)
                    > cfg.map_margin
                    && is_rival(&winner, &found, search, points, cfg) =>
            {
                (
                    Guarded::SearchedMap { score: found.score },
                    Some(found.pose),
                )
            }
            (Some(winner), _) => (
                Guarded::Searched {
                    score: winner.score,
                },
                Some(winner.pose),
            ),
            (None, Some(found)) => (
                Guarded::SearchedMap { score: found.score },
                Some(found.pose),
            ),
            (None, None) => (Guarded::NothingBetter, None),
        }
    }
}

/// Whether `found` is another peak than `winner` (the keyframe's answer) that fits the keyframe
/// (`keyframe`, its search grid) about as well: a pose the keyframe cannot rule out.
fn is_rival(
    winner: &Found,
    found: &Found,
    keyframe: &LookupGrid,
    points: &[Vec2],
    cfg: &GuardConfig,
) -> bool {
    let (shift, turn) = found.pose.distance_to(winner.pose);
    let rival = cfg.map_rival;
    (shift > rival.exclude_m || turn > rival.exclude_rad)
        && keyframe.score_pose(points, found.pose, &cfg.correlative) >= rival.ratio * winner.score
}

/// A search pyramid of the `recent` keyframes, in the frame of `keyframe` (the current one),
/// their points within `reach` of it.
fn local_map(
    recent: &std::collections::VecDeque<Keyframe>,
    keyframe: &Keyframe,
    reach: f32,
    config: &CorrelativeConfig,
) -> LookupGrid {
    let to_current = keyframe.tracking_pose.inverse();
    let points: Vec<Vec2> = recent
        .iter()
        .flat_map(|k| {
            let pose = to_current.compose(k.tracking_pose);
            k.points().map(move |p| pose.transform(p))
        })
        .filter(|p| p.norm() <= reach)
        .collect();
    LookupGrid::new(&points, 0.5, config, 5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_core::scan::Beam;

    /// A keyframe at the origin of the tracker's frame that saw `points` (its own frame).
    fn keyframe(points: &[Vec2], stamp_s: f64) -> Keyframe {
        Keyframe {
            stamp_s,
            beams: points
                .iter()
                .map(|p| Beam::new(p.y.atan2(p.x), p.norm()))
                .collect(),
            tracking_pose: Pose2::IDENTITY,
            submap: 0,
            path_m: 0.0,
            predicted: false,
        }
    }

    /// A corridor 2 m wide from x = -3 to 3 (its side walls), closed at x = 3 (its end wall).
    fn corridor() -> (Vec<Vec2>, Vec<Vec2>) {
        let sides = (0..=60)
            .flat_map(|i| {
                let x = i as f32 * 0.1 - 3.0;
                [Vec2::new(x, 1.0), Vec2::new(x, -1.0)]
            })
            .collect();
        let end = (0..=72)
            .map(|i| Vec2::new(3.0, i as f32 * 0.025 - 0.9))
            .collect();
        (sides, end)
    }

    /// The current keyframe saw only the corridor's side walls, which look the same turned a
    /// half turn; the keyframe before it also saw the end wall. A scan at `truth` sees the
    /// side walls and the end wall, and the guess is near the half-turned pose. Returns what
    /// the guard made of it with `config`.
    fn decide(config: GuardConfig, truth: Pose2) -> (Guarded, Option<Pose2>) {
        let (sides, end) = corridor();
        let all: Vec<Vec2> = sides.iter().chain(&end).copied().collect();
        let older = keyframe(&all, 0.0);
        let current = keyframe(&sides, 1.0);
        let scan: Vec<Vec2> = sides
            .iter()
            .filter(|p| p.x.abs() <= 2.5)
            .chain(&end)
            .map(|&p| truth.inverse().transform(p))
            .collect();
        let mut guard = GuessGuard::new(config);
        // The older keyframe is checked first, so the guard keeps it among the last ones.
        let (kept, _) = guard.check(&older, 0, &scan, truth, 0.2);
        assert_eq!(kept, Guarded::GuessKept);
        let half_turned = Pose2::new(-truth.x, -truth.y, truth.theta + std::f32::consts::PI);
        let guess = half_turned.compose(Pose2::new(0.0, 0.3, -0.3));
        guard.check(&current, 1, &scan, guess, 2.0)
    }

    #[test]
    fn the_last_keyframes_choose_between_poses_the_keyframe_cannot_tell_apart() {
        let truth = Pose2::new(0.5, 0.0, 0.0);
        let (guarded, found) = decide(GuardConfig::default(), truth);
        assert!(
            matches!(guarded, Guarded::SearchedMap { .. }),
            "{guarded:?}"
        );
        let (shift, turn) = found.expect("a pose").distance_to(truth);
        assert!(shift < 0.15 && turn < 0.05, "{found:?}");
        // Without the local map's say the keyframe's own winner stands: the half turn.
        let blind = GuardConfig {
            map_margin: f32::INFINITY,
            ..GuardConfig::default()
        };
        let (guarded, found) = decide(blind, truth);
        assert!(matches!(guarded, Guarded::Searched { .. }), "{guarded:?}");
        let (_, turn) = found.expect("a pose").distance_to(truth);
        assert!(turn > 3.0, "{found:?}");
    }
}
