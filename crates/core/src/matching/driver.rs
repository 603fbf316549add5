//! The iteration shared by `icl`, `plicp` and `icp`: associate, solve, keep degenerate
//! directions at the guess, test convergence and divergence, then report quality.

use super::associate::{associate, Partners, PassGate, PassStats, NO_PARTNER};
use super::config::MatchConfig;
use super::linalg::sym2_eigen;
use super::metrics::Solve;
use super::prepared::PreparedScan;
use super::result::{MatchError, MatchQuality, MatchResult, MatchStatus, UNOBSERVED_VARIANCE};
use crate::geom::{Pose2, Vec2};

/// A pass that moved the pose less than this leaves every point within a beam or so of its
/// partner, so the next pass may search around the partners (`associate::Partners`).
const SETTLED_STEP_M: f32 = 0.01;
const SETTLED_STEP_RAD: f32 = 0.004;

/// Smallest robust residual deviation assumed, m: below the range noise of any lidar.
const MIN_SIGMA_M: f32 = 0.005;

pub fn run<S: Solve, const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    guess: Pose2,
    previous_translation: Vec2,
    cfg: &MatchConfig,
    partners: &mut [u16],
) -> Result<MatchResult, MatchError> {
    let needed = cfg.min_points.max(3);
    let mut pose = guess;
    let mut sigma = cfg.max_correspondence_m / cfg.gate_sigmas.max(1.0);
    let mut dynamic = cfg.dynamic_rejection.then(|| {
        cfg.dynamic_gain * previous_translation.norm_squared()
            + cfg.dynamic_floor_m * cfg.dynamic_floor_m
    });
    let mut rejected_dynamic = 0;
    let mut status = MatchStatus::IterationLimit;
    let mut iterations = 0;
    let mut last = PassStats::default();
    let mut degenerate = None;
    // Partners from the last pass are good search seeds only once the pose has nearly settled:
    // an early pass can turn the scan by more beams than the search window covers.
    let mut settled = false;
    let mut previous_step = None;
    while iterations < cfg.max_iterations.max(1) {
        let first = iterations == 0;
        let gate_m = if first {
            cfg.max_correspondence_m
        } else {
            (cfg.gate_sigmas * sigma).clamp(cfg.min_gate_m, cfg.max_correspondence_m)
        };
        let gate = PassGate {
            gate_m,
            kernel_m: 2.0 * gate_m / cfg.gate_sigmas.max(1.0),
            dynamic_threshold_m2: dynamic.filter(|_| first),
        };
        let (mut stats, mut acc) = associate::<S, N>(
            reference,
            current,
            pose,
            &gate,
            cfg,
            Partners {
                slots: &mut *partners,
                reuse: !first && settled,
            },
        );
        if first && stats.rejected_dynamic as usize * 2 > current.len() {
            // Seed 000 sec. 4.2 assumes a good guess; when it rejects most of the scan the guess
            // is off, not the world. Redo the pass without it.
            dynamic = None;
            (stats, acc) = associate(
                reference,
                current,
                pose,
                &PassGate {
                    dynamic_threshold_m2: None,
                    ..gate
                },
                cfg,
                Partners {
                    slots: &mut *partners,
                    reuse: !first && settled,
                },
            );
        }
        if first {
            rejected_dynamic = stats.rejected_dynamic;
        }
        iterations += 1;
        if stats.inliers < needed {
            return Err(MatchError::TooFewCorrespondences {
                found: stats.inliers,
                needed,
            });
        }
        sigma = stats.robust_sigma.max(MIN_SIGMA_M);
        let mut next = acc.solve(&stats, pose).ok_or(MatchError::Diverged)?;
        degenerate = degenerate_direction(&stats, cfg.degenerate_ratio);
        if let Some(v) = degenerate {
            // Keep the unobserved component of the translation where the guess put it.
            let d = next.translation() - pose.translation();
            let along = v * d.dot(v);
            next = Pose2::new(next.x - along.x, next.y - along.y, next.theta);
        }
        let (dt, dr) = guess.distance_to(next);
        if !next.is_finite() || dt > cfg.max_correction_m || dr > cfg.max_correction_rad {
            return Err(MatchError::Diverged);
        }
        let (step_t, step_r) = pose.distance_to(next);
        settled = step_t < SETTLED_STEP_M && step_r < SETTLED_STEP_RAD;
        pose = next;
        last = stats;
        let step = (step_t / cfg.convergence_m).max(step_r / cfg.convergence_rad);
        if converged(step, previous_step) {
            status = MatchStatus::Converged;
            break;
        }
        previous_step = Some(step);
    }
    if degenerate.is_none() && !S::TO_POINT && cfg.localizability_check_below > 0.0 {
        degenerate = unsupported_direction(reference, current, pose, &last, cfg, partners);
        if let Some(v) = degenerate {
            pose = hold_along(pose, guess, v);
        }
    }
    Ok(report(
        pose,
        &last,
        degenerate,
        current.len(),
        iterations,
        rejected_dynamic,
        status,
    ))
}

/// Whether the iteration has converged after a step of `step` tolerances (the larger of
/// translation over `convergence_m` and rotation over `convergence_rad`) that followed one of
/// `previous` (none after the first pass): the step itself is within tolerance, or the steps
/// shrink so fast that all those still to come (a geometric series at the observed ratio) add
/// up to less than the tolerance, which a step of one tolerance or more passes only at ratios
/// below one half. The second case saves the pass that would only confirm a step already below
/// a millimetre.
fn converged(step: f32, previous: Option<f32>) -> bool {
    let settles = |previous: f32| {
        let ratio = step / previous;
        ratio < 1.0 && step * ratio / (1.0 - ratio) < 1.0
    };
    step < 1.0 || previous.is_some_and(settles)
}

/// `pose` with its translation along the unit `v` moved back to where `guess` put it (Zhang,
/// Kaess and Singh's solution remapping: along a direction the data do not constrain, the
/// prior is kept and only the constrained part of the solution is used).
pub(super) fn hold_along(pose: Pose2, guess: Pose2, v: Vec2) -> Pose2 {
    let along = v * v.dot(pose.translation() - guess.translation());
    Pose2::new(pose.x - along.x, pose.y - along.y, pose.theta)
}

/// The least-constrained translation direction of a converged match when too few of its
/// points face along it for the motion along it to be measured, if so.
///
/// The eigenvalue test alone ([`degenerate_direction`]) is fooled by noise: in a room or
/// corridor lined with parallel walls, the fitted normals of noisy points tilt by a few degrees,
/// and each tilted line lends the direction a little information that is really the offset of
/// the point along its wall. Summed over a scan it passes the ratio test, and the matches it
/// gives slide along the walls by tenths of a metre (the simulator's XV-11 surveys of long
/// rooms). What does measure motion along a direction is a surface facing it (a wall end, a
/// door frame, a corner), so a direction counts as measured only when at least
/// [`MatchConfig::min_facing_points`] matched points have normals within
/// [`MatchConfig::facing_max_angle_rad`] of it (the per-point view of localizability used by
/// X-ICP, Tuna et al. 2023). The count runs only for matches whose conditioning is below
/// [`MatchConfig::localizability_check_below`], so well-constrained matches pay nothing.
fn unsupported_direction<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    pose: Pose2,
    stats: &PassStats,
    cfg: &MatchConfig,
    partners: &[u16],
) -> Option<Vec2> {
    let (a, b, c) = stats.information.translation_schur();
    let (hi, lo, v) = sym2_eigen(a, b, c);
    if hi.is_nan() || hi <= 0.0 || lo >= cfg.localizability_check_below * hi {
        return None;
    }
    let min_cos = libm::cosf(cfg.facing_max_angle_rad);
    let gate_m = (cfg.gate_sigmas * stats.robust_sigma.max(MIN_SIGMA_M))
        .clamp(cfg.min_gate_m, cfg.max_correspondence_m);
    let (s, co) = (libm::sinf(pose.theta), libm::cosf(pose.theta));
    let t = pose.translation();
    let mut facing = 0u16;
    for (&p, &j) in current.points().iter().zip(partners) {
        if j == NO_PARTNER {
            continue;
        }
        let j = j as usize;
        let Some(n) = reference.line(j).normal() else {
            continue;
        };
        if libm::fabsf(n.dot(v)) < min_cos {
            continue;
        }
        let q = Vec2::new(co * p.x - s * p.y, s * p.x + co * p.y) + t;
        if libm::fabsf(n.dot(q - reference.point(j))) <= gate_m {
            facing += 1;
            if facing >= cfg.min_facing_points {
                return None;
            }
        }
    }
    Some(v)
}

/// The translation direction the pass's information does not pin down, if any.
fn degenerate_direction(stats: &PassStats, ratio: f32) -> Option<Vec2> {
    stats.information.weak_translation(ratio).map(|(_, v)| v)
}

#[allow(clippy::too_many_arguments)]
pub fn report(
    motion: Pose2,
    stats: &PassStats,
    degenerate: Option<Vec2>,
    points: usize,
    iterations: u16,
    rejected_dynamic: u16,
    status: MatchStatus,
) -> MatchResult {
    let (a, b, c) = stats.information.translation_schur();
    let (hi, lo, _) = sym2_eigen(a, b, c);
    let conditioning = if hi > 0.0 { (lo / hi).max(0.0) } else { 0.0 };
    let dof = (stats.weight_sum - 3.0).max(1.0);
    let s2 = (stats.weighted_sq_sum / dof).max(MIN_SIGMA_M * MIN_SIGMA_M * 0.25);
    let (covariance, observed_covariance) = covariances(stats, degenerate, s2);
    let inliers = stats.inliers;
    MatchResult {
        motion,
        covariance,
        observed_covariance,
        quality: MatchQuality {
            status,
            iterations,
            points: points as u16,
            inliers,
            inlier_ratio: if points > 0 {
                inliers as f32 / points as f32
            } else {
                0.0
            },
            rms_residual_m: if inliers > 0 {
                libm::sqrtf(stats.sq_sum / inliers as f32)
            } else {
                0.0
            },
            rejected_dynamic,
            degenerate_direction: degenerate,
            conditioning,
            recovered: false,
        },
    }
}

/// s² times the inverse information, and the part of it the match observed. Along a
/// degenerate direction the full covariance has [`UNOBSERVED_VARIANCE`] and the observed one
/// nothing (see [`MatchResult::observed_covariance`]).
fn covariances(
    stats: &PassStats,
    degenerate: Option<Vec2>,
    s2: f32,
) -> ([[f32; 3]; 3], [[f32; 3]; 3]) {
    let h = stats.information;
    match (degenerate, h.inverse()) {
        (None, Some(inv)) => {
            let m = inv.to_array();
            let full = core::array::from_fn(|i| core::array::from_fn(|j| s2 * m[i][j]));
            (full, full)
        }
        _ => {
            let (a, b, c) = h.translation_schur();
            let (hi, _, v_lo) = sym2_eigen(a, b, c);
            let var_hi = if hi > 0.0 {
                s2 / hi
            } else {
                UNOBSERVED_VARIANCE
            };
            let var_rot = if h.tt > 0.0 {
                s2 / h.tt
            } else {
                UNOBSERVED_VARIANCE
            };
            let matrix = |var_lo: f32| split_covariance(v_lo, var_hi, var_lo, var_rot);
            let full = matrix(UNOBSERVED_VARIANCE);
            // Without a reported degenerate direction (the information only failed to invert)
            // a filter has no axis to leave out, so it gets the full covariance.
            let observed = if degenerate.is_some() {
                matrix(0.0)
            } else {
                full
            };
            (full, observed)
        }
    }
}

/// The covariance of a match whose translation information has its weakest direction along the
/// unit `v_lo` (variance `var_lo`) and its strongest across it (`var_hi`), with heading variance
/// `var_rot` and no correlation between them (the degenerate case's shape).
pub(super) fn split_covariance(
    v_lo: Vec2,
    var_hi: f32,
    var_lo: f32,
    var_rot: f32,
) -> [[f32; 3]; 3] {
    let v_hi = v_lo.perp();
    let t = |i: usize, j: usize| {
        let (hi_i, hi_j) = ([v_hi.x, v_hi.y][i], [v_hi.x, v_hi.y][j]);
        let (lo_i, lo_j) = ([v_lo.x, v_lo.y][i], [v_lo.x, v_lo.y][j]);
        hi_i * var_hi * hi_j + lo_i * var_lo * lo_j
    };
    [
        [t(0, 0), t(0, 1), 0.0],
        [t(1, 0), t(1, 1), 0.0],
        [0.0, 0.0, var_rot],
    ]
}

#[cfg(test)]
mod tests {
    use super::converged;

    #[test]
    fn a_step_within_tolerance_converges_on_any_pass() {
        assert!(converged(0.9, None));
        assert!(converged(0.9, Some(0.95)));
    }

    #[test]
    fn a_larger_step_converges_only_when_the_steps_to_come_sum_within_tolerance() {
        // First pass: nothing to extrapolate from.
        assert!(!converged(2.0, None));
        // Ratio 0.1: the steps still to come sum to about 0.22 tolerances.
        assert!(converged(2.0, Some(20.0)));
        // Ratio 0.3: they sum to about 1.3 tolerances.
        assert!(!converged(3.0, Some(10.0)));
        // Ratio 0.67: they sum to 4 tolerances.
        assert!(!converged(2.0, Some(3.0)));
        // A growing step is no contraction (its series has no sum).
        assert!(!converged(2.0, Some(1.5)));
    }
}
