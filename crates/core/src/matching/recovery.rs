//! Recovery from a bad initial guess: a coarse search over heading.
//!
//! A turning vehicle can rotate tens of degrees between two revolutions, and iterative matchers
//! only converge from within a few degrees. Heading is what goes wrong most (translation per
//! revolution is small indoors), so candidates around the guess are scored by how many current
//! points land near a reference point, and the best one seeds a second match.

use super::config::MatchConfig;
use super::prepared::PreparedScan;
use crate::geom::{Pose2, Vec2};

/// The heading candidate (translation kept from `guess`) under which most points find a
/// reference point within `radius_m`.
pub fn best_heading<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    guess: Pose2,
    cfg: &MatchConfig,
) -> Pose2 {
    let steps = (cfg.recovery_range_rad / cfg.recovery_step_rad.max(1e-3)) as i32;
    let r2 = cfg.recovery_radius_m * cfg.recovery_radius_m;
    let window = cfg.search_half_window as usize;
    let mut best = (0usize, guess);
    for k in -steps..=steps {
        let candidate = Pose2::new(
            guess.x,
            guess.y,
            guess.theta + k as f32 * cfg.recovery_step_rad,
        );
        let mut hint = 0;
        let mut hits = 0;
        for &p in current.points() {
            let q = candidate.transform(p);
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
            best = (hits, candidate);
        }
    }
    best.1
}
