//! Scan-to-scan matching (seed 000 sec. 4): how the vehicle moved between two revolutions.
//!
//! [`ScanMatcher`] holds a prepared reference scan and matches new scans against it with the
//! configured [`MatcherKind`]. All state is inline, sized by the const generic `N` (beams per
//! scan), so `size_of::<ScanMatcher<360>>()` is the whole RAM cost.

mod associate;
mod config;
mod driver;
mod edges;
mod fit_lanes;
mod icl_paper;
mod line_sums;
mod line_fit;
pub(crate) mod linalg;
pub mod local_map;
mod metrics;
mod nearest;
mod odometry;
mod prepared;
mod prior_fusion;
mod recovery;
mod result;
mod window;

pub use config::{MatchConfig, MatcherKind};
pub use icl_paper::{closest_point_on_line, PaperMatch, PaperRejection};
pub use odometry::{LidarOdometry, MotionLimits, OdometryConfig, OdometryStep};
pub use prepared::PreparedScan;
pub use prior_fusion::PriorFusion;
pub use result::{MatchError, MatchQuality, MatchResult, MatchStatus, UNOBSERVED_VARIANCE};

use crate::geom::{Pose2, Vec2};
use crate::scan::Scan;
use associate::{Partners, PassGate};
use metrics::{PointToLineGaussNewton, PointToPointClosedForm, PointToSegmentExact};
use recovery::SearchBox;

/// A scan matcher with room for scans of up to `N` beams.
#[derive(Clone, Debug)]
pub struct ScanMatcher<const N: usize> {
    config: MatchConfig,
    /// Two scan slots; `reference` says which one is the reference.
    slots: [PreparedScan<N>; 2],
    reference: usize,
    has_reference: bool,
    /// Translation of the previous match, for the seed 000 sec. 4.2 test.
    previous_translation: Vec2,
    /// Matches left before a low inlier ratio alone may start a search again.
    search_rest: u8,
    /// Each current point's partner in the last association pass (see `associate::Partners`).
    partners: [u16; N],
}

impl<const N: usize> ScanMatcher<N> {
    pub fn new(config: MatchConfig) -> Self {
        Self {
            config,
            slots: [PreparedScan::default(), PreparedScan::default()],
            reference: 0,
            has_reference: false,
            previous_translation: Vec2::ZERO,
            search_rest: 0,
            partners: [associate::NO_PARTNER; N],
        }
    }

    pub fn config(&self) -> &MatchConfig {
        &self.config
    }

    /// The reference scan's valid points, in its own frame (empty before the first reference).
    pub fn reference_points(&self) -> &[Vec2] {
        if self.has_reference {
            self.slots[self.reference].points()
        } else {
            &[]
        }
    }

    pub fn has_reference(&self) -> bool {
        self.has_reference
    }

    /// Makes `scan` the reference that later scans are matched against.
    pub fn set_reference(&mut self, scan: &Scan<N>) -> Result<(), MatchError> {
        self.has_reference = false;
        let slot = &mut self.slots[self.reference];
        slot.load(scan)?;
        slot.fit_lines(
            self.config.line_neighbour_m,
            self.config.line_max_flatness,
            self.config.line_min_extent_m,
        );
        self.has_reference = true;
        Ok(())
    }

    /// Makes the scan of the last `match_scan` call the reference, without preparing it again.
    pub fn promote_current(&mut self) {
        self.reference ^= 1;
        let slot = &mut self.slots[self.reference];
        slot.fit_lines(
            self.config.line_neighbour_m,
            self.config.line_max_flatness,
            self.config.line_min_extent_m,
        );
        self.has_reference = true;
    }

    /// Where `scan` was taken, in the reference scan's frame, starting from `guess`.
    pub fn match_scan(&mut self, scan: &Scan<N>, guess: Pose2) -> Result<MatchResult, MatchError> {
        if !guess.is_finite() {
            return Err(MatchError::NonFiniteGuess);
        }
        if !self.has_reference {
            return Err(MatchError::NoReference);
        }
        let [a, b] = &mut self.slots;
        let (reference, current) = if self.reference == 0 {
            (&*a, b)
        } else {
            (&*b, a)
        };
        current.load(scan)?;
        let cfg = &self.config;
        let needed = cfg.min_points.max(3);
        if reference.len() < needed as usize || current.len() < needed as usize {
            return Err(MatchError::TooFewPoints {
                reference: reference.len() as u16,
                current: current.len() as u16,
                needed,
            });
        }
        let prev = self.previous_translation;
        let partners = &mut self.partners;
        let mut attempt = |guess: Pose2| match cfg.kind {
            MatcherKind::Icl => driver::run::<PointToLineGaussNewton, N>(
                reference, current, guess, prev, cfg, partners,
            ),
            MatcherKind::Plicp => driver::run::<PointToSegmentExact, N>(
                reference, current, guess, prev, cfg, partners,
            ),
            MatcherKind::Icp => driver::run::<PointToPointClosedForm, N>(
                reference, current, guess, prev, cfg, partners,
            ),
            MatcherKind::IclPaper => {
                let rejection = cfg.paper_rejection.then_some(PaperRejection {
                    previous: prev,
                    gain: cfg.dynamic_gain,
                    floor_m: cfg.paper_rejection_floor_m,
                });
                let found = icl_paper::run(
                    reference,
                    current,
                    guess,
                    cfg.paper_rate_per_point,
                    cfg.paper_iterations,
                    rejection,
                );
                Self::paper_report(reference, current, found, cfg, partners)
            }
        };
        let first = attempt(guess);
        let is_hard = |r: &Result<MatchResult, MatchError>| match r {
            Ok(r) => r.quality.status == MatchStatus::IterationLimit,
            Err(e) => matches!(
                e,
                MatchError::TooFewCorrespondences { .. } | MatchError::Diverged
            ),
        };
        let is_sparse = |r: &Result<MatchResult, MatchError>| {
            r.as_ref()
                .is_ok_and(|r| r.quality.inlier_ratio < cfg.recovery_below_inlier_ratio)
        };
        let mut result = first;
        let rested = self.search_rest == 0;
        self.search_rest = self.search_rest.saturating_sub(1);
        if cfg.recovery && cfg.kind != MatcherKind::IclPaper {
            let mut searched_on_ratio = false;
            for search in [SearchBox::heading(cfg), SearchBox::pose(cfg)] {
                let hard = is_hard(&result);
                if !(hard || (rested && is_sparse(&result))) {
                    break;
                }
                searched_on_ratio |= !hard;
                let seed = recovery::best_pose(reference, current, guess, search, cfg);
                let second = attempt(seed);
                result = match (&result, second) {
                    (Ok(a), Ok(b)) if a.quality.inliers >= b.quality.inliers => result,
                    (_, Ok(b)) => Ok(MatchResult {
                        quality: MatchQuality {
                            recovered: true,
                            ..b.quality
                        },
                        ..b
                    }),
                    (_, Err(_)) => result,
                };
            }
            let rescued = result.as_ref().is_ok_and(|r| r.quality.recovered);
            if searched_on_ratio && !rescued {
                self.search_rest = cfg.recovery_rest_matches;
            }
        }
        let mut result = result?;
        if let (true, Some(v)) = (
            result.quality.recovered && cfg.localizability_check_below > 0.0,
            result.quality.degenerate_direction,
        ) {
            // The search's scores are as flat along a degenerate direction as the match's
            // information, so where along it the search started says nothing: the caller's
            // guess stays the prior there, as it does for a match made from the guess itself.
            // Only for the noisy lidars the localizability check is on for: a SICK scan's
            // wall ends measure the direction from where the search put it (the point passes
            // below), while a lidar-only guess is the last motion repeated, stale whenever the
            // vehicle speeds up or stops between scans far apart (Intel thinned to every 8th
            // scan slid 0.4 m at a time along corridors and ended 2.19 m off instead of 0.028).
            result.motion = driver::hold_along(result.motion, guess, v);
        }
        if cfg.kind == MatcherKind::Icl {
            fill_degenerate_direction(reference, current, &mut result, prev, cfg, &mut *partners);
        }
        self.previous_translation = result.motion.translation();
        Ok(result)
    }

    /// The paper's method has no quality measure of its own; score its answer with one pass
    /// of the shared association so every matcher reports the same fields.
    fn paper_report(
        reference: &PreparedScan<N>,
        current: &PreparedScan<N>,
        found: PaperMatch,
        cfg: &MatchConfig,
        partners: &mut [u16],
    ) -> Result<MatchResult, MatchError> {
        let motion = found.pose;
        if !motion.is_finite() {
            return Err(MatchError::Diverged);
        }
        let gate = PassGate {
            gate_m: cfg.max_correspondence_m,
            kernel_m: cfg.max_correspondence_m,
            dynamic_threshold_m2: None,
        };
        let partners = Partners {
            slots: partners,
            reuse: false,
        };
        let (stats, _) = associate::associate::<PointToLineGaussNewton, N>(
            reference, current, motion, &gate, cfg, partners,
        );
        Ok(driver::report(
            motion,
            &stats,
            None,
            current.len(),
            cfg.paper_iterations,
            found.rejected,
            MatchStatus::IterationLimit,
        ))
    }
}

/// Where `icl` found a translation direction degenerate (a corridor's axis), measures the
/// motion along it with what the line metric cannot see.
///
/// First a few point-to-point passes move the answer along the direction to where they put
/// it: the line metric leaves the guess there, and lidar-only odometry would carry a constant
/// velocity down the whole corridor. Measured on the simulator's office survey with the XV-11
/// (4 m range): near-relation error 3.2 -> 1.6 cm (BENCHMARKS.md). In a featureless corridor
/// they find nothing and stay near the guess (test). They give no variance, so the direction
/// stays degenerate after them.
///
/// Then the wall ends both scans see ([`edges`]: door frames, openings) measure the motion
/// along the direction with a variance of their own. Where at least two pairs agree the
/// direction is observed: the answer moves to theirs, its variance is theirs, and the
/// direction is no longer reported degenerate. Heading and the other direction stay the line
/// metric's.
fn fill_degenerate_direction<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    result: &mut MatchResult,
    previous_translation: Vec2,
    cfg: &MatchConfig,
    partners: &mut [u16],
) {
    let Some(v) = result.quality.degenerate_direction else {
        return;
    };
    if cfg.degenerate_point_passes > 0 {
        let passes = MatchConfig {
            max_iterations: cfg.degenerate_point_passes,
            // The line metric's pass already applied seed 000's test at the guess.
            dynamic_rejection: false,
            ..*cfg
        };
        if let Ok(points) = driver::run::<PointToPointClosedForm, N>(
            reference,
            current,
            result.motion,
            previous_translation,
            &passes,
            partners,
        ) {
            let along = v * v.dot(points.motion.translation() - result.motion.translation());
            let m = result.motion;
            result.motion = Pose2::new(m.x + along.x, m.y + along.y, m.theta);
        }
    }
    let Some(ends) = edges::measure_along(reference, current, result.motion, v, cfg) else {
        return;
    };
    let m = result.motion;
    result.motion = Pose2::new(m.x + v.x * ends.shift_m, m.y + v.y * ends.shift_m, m.theta);
    // The observed covariance has nothing along `v`: projecting the full one (with
    // UNOBSERVED_VARIANCE along `v`) across it would leave only rounding error in f32.
    let c = &result.observed_covariance;
    let across = v.perp();
    let var_across = across.x * across.x * c[0][0]
        + 2.0 * across.x * across.y * c[0][1]
        + across.y * across.y * c[1][1];
    let covariance = driver::split_covariance(v, var_across, ends.variance_m2, c[2][2]);
    result.covariance = covariance;
    result.observed_covariance = covariance;
    result.quality.degenerate_direction = None;
    result.quality.conditioning =
        var_across.min(ends.variance_m2) / var_across.max(ends.variance_m2);
}
