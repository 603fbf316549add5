//! Recovery from a bad initial guess: a coarse search for a better starting pose.
//!
//! A turning vehicle can rotate tens of degrees between two revolutions, and iterative matchers
//! only converge from within a few degrees. Heading is what goes wrong most, so the first search
//! is over heading alone; logs decimated to one scan a metre (the SLAM-corrected Radish logs)
//! also need translation, searched on a grid over a subsample of the points. Candidates are
//! scored by how many current points land near a reference point.

use super::config::MatchConfig;
use super::prepared::PreparedScan;
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
/// within `cfg.recovery_radius_m`.
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
    let r2 = cfg.recovery_radius_m * cfg.recovery_radius_m;
    let window = cfg.search_half_window as usize;
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
