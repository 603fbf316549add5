//! Recovery from a bad initial guess: a coarse search for a better starting pose.
//!
//! A turning vehicle can rotate tens of degrees between two revolutions, and iterative matchers
//! only converge from within a few degrees. Heading is what goes wrong most, so the first search
//! is over heading alone; logs decimated to one scan a metre (the SLAM-corrected Radish logs)
//! also need translation, searched on a grid over a subsample of the points. Candidates are
//! scored by how many current points land near a reference point.

use super::config::MatchConfig;
use super::prepared::PreparedScan;
use super::window::{any_within_six, usual_window};
use crate::geom::{Pose2, Vec2};

/// A box of candidate poses around a guess.
#[derive(Clone, Copy, Debug)]
pub struct SearchBox {
    pub heading_range_rad: f32,
    pub heading_step_rad: f32,
    pub translation_range_m: f32,
    pub translation_step_m: f32,
    /// Score every `point_stride`-th current point.
    pub point_stride: usize,
}

impl SearchBox {
    pub fn heading(cfg: &MatchConfig) -> Self {
        Self {
            heading_range_rad: cfg.recovery_range_rad,
            heading_step_rad: cfg.recovery_step_rad,
            translation_range_m: 0.0,
            translation_step_m: 1.0,
            point_stride: 1,
        }
    }

    /// Translation and heading together, coarser and on a subsample: the heading found alone
    /// can be wrong when translation is far off, so the full heading range is searched again.
    pub fn pose(cfg: &MatchConfig) -> Self {
        Self {
            heading_range_rad: cfg.recovery_range_rad,
            heading_step_rad: 2.0 * cfg.recovery_step_rad,
            translation_range_m: cfg.recovery_translation_m,
            translation_step_m: cfg.recovery_radius_m * 1.5,
            point_stride: 4,
        }
    }
}

/// The candidate in `search` around `guess` under which most points find a reference point
/// within `cfg.recovery_radius_m` (the first in search order among equals: heading, then x,
/// then y, each from the lowest; the guess itself if no candidate scores a point).
///
/// Most candidates are far off, and a candidate is dropped as soon as its remaining points
/// cannot lift it to the count it needs: that of the best so far (one more if the best comes
/// first in search order), and at least the guess's own count (the best is never below that,
/// so a candidate short of it can never be the answer). The candidates are counted from the
/// guess outwards, so that a good count, usually found near the guess, sets that bar early and
/// the far candidates are dropped after fewer points. The answer is the one a full count of
/// every candidate in search order gives.
///
/// Out of line: inlined, its frame (a heading's sine and cosine kept across all its
/// translations) joined the match's, the deepest of the bare build's stack.
#[inline(never)]
pub fn best_pose<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    guess: Pose2,
    search: SearchBox,
    cfg: &MatchConfig,
) -> Pose2 {
    let steps = |range: f32, step: f32| (range / step.max(1e-3)) as i32;
    let nh = steps(search.heading_range_rad, search.heading_step_rad);
    let nt = steps(search.translation_range_m, search.translation_step_m);
    let counter = HitCounter {
        reference,
        current,
        stride: search.point_stride.max(1),
        r2: cfg.recovery_radius_m * cfg.recovery_radius_m,
        window: cfg.search_half_window as usize,
    };
    // Heading unwrapped (the rotation is taken of it as it is), turned into a sine and cosine
    // once for all the translations tried with it, and translation.
    let heading = |k: i32| guess.theta + k as f32 * search.heading_step_rad;
    let turn = |theta: f32| (libm::sinf(theta), libm::cosf(theta));
    let place = |ix: i32, iy: i32| {
        Vec2::new(
            guess.x + ix as f32 * search.translation_step_m,
            guess.y + iy as f32 * search.translation_step_m,
        )
    };
    // A candidate's place in search order.
    let side = 2 * i64::from(nt) + 1;
    let order = |k: i32, ix: i32, iy: i32| {
        (i64::from(k + nh) * side + i64::from(ix + nt)) * side + i64::from(iy + nt)
    };
    // The guess first: its count is the floor.
    let floor = counter.hits(turn(heading(0)), place(0, 0), 0);
    // (count, pose, place in search order) of the best candidate so far.
    let mut best = (0usize, guess, i64::MAX);
    if floor > 0 {
        best = (
            floor,
            Pose2::new(place(0, 0).x, place(0, 0).y, heading(0)),
            order(0, 0, 0),
        );
    }
    for k in outwards(nh) {
        let theta = heading(k);
        let rotation = turn(theta);
        for ix in outwards(nt) {
            for iy in outwards(nt) {
                if (k, ix, iy) == (0, 0, 0) {
                    continue;
                }
                let at = order(k, ix, iy);
                let beats = best.0 + usize::from(at > best.2);
                let need = beats.max(floor).max(1);
                let t = place(ix, iy);
                let hits = counter.hits(rotation, t, need);
                if hits >= need {
                    best = (hits, Pose2::new(t.x, t.y, theta), at);
                }
            }
        }
    }
    best.1
}

/// `0, -1, 1, -2, 2, ..., -n, n`: steps of a search from its centre outwards.
fn outwards(n: i32) -> impl Iterator<Item = i32> {
    (0..=2 * n).map(|m| if m % 2 == 0 { m / 2 } else { -(m + 1) / 2 })
}

/// Counts the points of `current` (every `stride`-th) that find a point of `reference` within
/// the recovery radius.
struct HitCounter<'a, const N: usize> {
    reference: &'a PreparedScan<N>,
    current: &'a PreparedScan<N>,
    stride: usize,
    r2: f32,
    window: usize,
}

impl<const N: usize> HitCounter<'_, N> {
    /// The count with the points turned by `(sin, cos)` and moved by `t`, exact when it
    /// reaches `need`; below `need` it may stop short (once the points left could not make up
    /// the difference).
    fn hits(&self, (s, c): (f32, f32), t: Vec2, need: usize) -> usize {
        let points = self.current.points();
        let reference = self.reference.points();
        let mut left = points.len().div_ceil(self.stride);
        let mut hint = 0;
        let mut hits = 0;
        for &p in points.iter().step_by(self.stride) {
            if hits + left < need {
                break;
            }
            left -= 1;
            let q = Vec2::new(c * p.x - s * p.y + t.x, s * p.x + c * p.y + t.y);
            // Points a beam apart: the usual query in one go (the projection a step on, the
            // window inside the scan), as the association passes make it. Else (and points
            // some beams apart rarely project within a step) the general projection and search.
            let usual = (self.window == 3 && self.stride == 1)
                .then(|| usual_window(reference, q, hint))
                .flatten();
            let near = match usual {
                Some((k, window)) => {
                    hint = k;
                    any_within_six(window, q, self.r2)
                }
                None => {
                    let Some(k) = self.reference.project(q, hint) else {
                        continue;
                    };
                    hint = k;
                    self.reference.near_in_window(q, k, self.window, self.r2)
                }
            };
            hits += near as usize;
        }
        hits
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::scan::{Beam, Scan};
    use std::vec::Vec;

    /// The search as a full count of every candidate: the answer the pruned one must give.
    fn full_count<const N: usize>(
        reference: &PreparedScan<N>,
        current: &PreparedScan<N>,
        guess: Pose2,
        search: SearchBox,
        cfg: &MatchConfig,
    ) -> Pose2 {
        let steps = |range: f32, step: f32| (range / step.max(1e-3)) as i32;
        let nh = steps(search.heading_range_rad, search.heading_step_rad);
        let nt = steps(search.translation_range_m, search.translation_step_m);
        let r2 = cfg.recovery_radius_m * cfg.recovery_radius_m;
        let mut best = (0usize, guess);
        for k in -nh..=nh {
            let theta = guess.theta + k as f32 * search.heading_step_rad;
            let (s, c) = (libm::sinf(theta), libm::cosf(theta));
            for ix in -nt..=nt {
                for iy in -nt..=nt {
                    let t = Vec2::new(
                        guess.x + ix as f32 * search.translation_step_m,
                        guess.y + iy as f32 * search.translation_step_m,
                    );
                    let mut hint = 0;
                    let mut hits = 0;
                    for &p in current.points().iter().step_by(search.point_stride.max(1)) {
                        let q = Vec2::new(c * p.x - s * p.y + t.x, s * p.x + c * p.y + t.y);
                        let Some(k) = reference.project(q, hint) else {
                            continue;
                        };
                        hint = k;
                        let window = cfg.search_half_window as usize;
                        if reference
                            .nearest_in_window(q, k, window)
                            .is_some_and(|(_, d2)| d2 <= r2)
                        {
                            hits += 1;
                        }
                    }
                    if hits > best.0 {
                        best = (hits, Pose2::new(t.x, t.y, theta));
                    }
                }
            }
        }
        best.1
    }

    /// A room of random wall distances seen all round from `at` (`beams` over a turn, or over
    /// 240 degrees).
    fn room(ranges: &[f32], full: bool) -> Scan<90> {
        let mut s = Scan::new(0.0);
        let span = if full { 360.0 } else { 240.0 };
        for (i, &r) in ranges.iter().enumerate() {
            let a = (-span / 2.0 + span * i as f32 / ranges.len() as f32).to_radians();
            s.push(Beam::new(a, r)).unwrap();
        }
        s
    }

    proptest::proptest! {
        /// Dropping candidates that can no longer win changes no answer: the same pose as a
        /// full count, for both searches, over rooms of smooth and of ragged walls, full
        /// turns and open fields of view, guesses near and far.
        #[test]
        fn pruned_search_finds_the_full_counts_answer(
            walls in proptest::collection::vec(0.5f32..6.0, 90),
            smooth in proptest::bool::ANY,
            full in proptest::bool::ANY,
            dx in -1.0f32..1.0, dy in -1.0f32..1.0, dtheta in -1.0f32..1.0,
        ) {
            let ranges: Vec<f32> = if smooth {
                (0..90).map(|i| 2.0 + 1.5 * libm::sinf(i as f32 * 0.2 + walls[0])).collect()
            } else {
                walls.clone()
            };
            let shifted: Vec<f32> = ranges.iter().cycle().skip(3).take(90).copied().collect();
            let cfg = MatchConfig::default();
            let mut reference: PreparedScan<90> = PreparedScan::default();
            let mut current: PreparedScan<90> = PreparedScan::default();
            reference.load(&room(&ranges, full)).unwrap();
            current.load(&room(&shifted, full)).unwrap();
            let guess = Pose2::new(dx, dy, dtheta);
            for search in [SearchBox::heading(&cfg), SearchBox::pose(&cfg)] {
                let pruned = best_pose(&reference, &current, guess, search, &cfg);
                let full = full_count(&reference, &current, guess, search, &cfg);
                proptest::prop_assert_eq!(pruned, full);
            }
        }
    }
}
