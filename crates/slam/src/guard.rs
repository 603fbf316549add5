//! A cheap check of the tracker's motion guess, and a wide search when it fails.
//!
//! The tracker starts each match from the last motion repeated (or the caller's prior). After a
//! sharp turn, a dropped scan, or in a log thinned to one scan in eight, that guess can be far
//! outside the basin the matcher converges from, and its own recovery searches only a small box.
//! So before every match the guess is scored against a likelihood grid of the current keyframe
//! (about a hundred look-ups); only when it fits badly does a branch-and-bound correlative
//! search over a wide window (Olson 2009) run and hand the tracker a better guess.

use crate::config::GuardConfig;
use crate::correlative::{LookupGrid, Window};
use crate::keyframe::Keyframe;
use plumbline_core::geom::{Pose2, Vec2};

/// What the check did for one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guarded {
    /// The guess fit (or there was nothing to check against).
    GuessKept,
    /// The guess fit badly and the search found a better one.
    Searched { score: f32 },
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
}

impl GuessGuard {
    pub fn new(config: GuardConfig) -> Self {
        Self {
            config,
            keyframe: None,
            check: None,
            search: None,
        }
    }

    /// The guess for a scan whose points are `points`, if the tracker's own should be replaced:
    /// `guess` is the scan's pose in the frame of keyframe `index` that the tracker will try.
    pub fn check(
        &mut self,
        keyframe: &Keyframe,
        index: usize,
        points: &[Vec2],
        guess: Pose2,
    ) -> (Guarded, Option<Pose2>) {
        let cfg = &self.config;
        if !cfg.enabled || points.is_empty() {
            return (Guarded::GuessKept, None);
        }
        // Scored points lie within `max_range_m` of the scan, and the scan within the window of
        // the keyframe: farther reference points cannot be reached and would only grow the grid.
        let reach = cfg.correlative.max_range_m + cfg.window_m;
        let reference =
            || -> Vec<Vec2> { keyframe.points().filter(|p| p.norm() <= reach).collect() };
        if self.keyframe != Some(index) {
            let reference = reference();
            self.check = Some(LookupGrid::new(&reference, 0.0, &cfg.correlative, 1));
            self.search = None;
            self.keyframe = Some(index);
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
        let window = Window {
            translation_m: cfg.window_m,
            heading_rad: cfg.window_rad,
        };
        let floor = (guess_score * cfg.min_gain).max(cfg.min_found_score);
        match search.search(points, guess, window, floor, &cfg.correlative) {
            Some(found) => (Guarded::Searched { score: found.score }, Some(found.pose)),
            None => (Guarded::NothingBetter, None),
        }
    }
}
