//! What a match returns: the motion, its covariance and a quality report — or why it failed.

use super::linalg::Sym3;
use super::prepared::PrepareError;
use crate::geom::{Pose2, Vec2};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatchStatus {
    Converged,
    /// Stopped at the iteration limit still moving; the motion is the last estimate.
    IterationLimit,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchQuality {
    pub status: MatchStatus,
    pub iterations: u16,
    /// Valid points in the current scan.
    pub points: u16,
    /// Points that found a reference partner inside the gate in the last pass.
    pub inliers: u16,
    pub inlier_ratio: f32,
    pub rms_residual_m: f32,
    /// Points rejected by the seed 000 sec. 4.2 test (moving people, spurious returns).
    pub rejected_dynamic: u16,
    /// Unit direction (reference frame) along which the scans do not constrain translation,
    /// e.g. the axis of a featureless corridor: neither wall lines nor wall ends measure it.
    /// The motion along it is the initial guess's (or the point-to-point passes').
    pub degenerate_direction: Option<Vec2>,
    /// Least over most translational information (1 = equally constrained in x and y).
    pub conditioning: f32,
    /// The first attempt failed or was poor and a heading search found a better start.
    pub recovered: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchResult {
    /// Pose of the current scan in the reference scan's frame.
    pub motion: Pose2,
    /// Covariance of (x, y, theta) in m² and rad². Along a degenerate direction the variance is
    /// [`UNOBSERVED_VARIANCE`], so a filter knows to ignore it.
    pub covariance: [[f32; 3]; 3],
    /// The covariance of what the match observed, for a filter that fuses only that: the same
    /// as `covariance` except along a degenerate direction, where its variance is zero instead
    /// of [`UNOBSERVED_VARIANCE`]. A filter projecting `covariance` across a degenerate
    /// direction that is not a coordinate axis gets the rounding error of the huge variance
    /// along it (1e4 times f32's 6e-8, against a few 1e-6 across): a variance that can come out
    /// negative, which no update can survive.
    pub observed_covariance: [[f32; 3]; 3],
    pub quality: MatchQuality,
}

/// Variance reported for what a match did not observe (m² or rad²).
pub const UNOBSERVED_VARIANCE: f32 = 1.0e4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MatchError {
    /// `match_scan` was called before any reference was set.
    NoReference,
    /// A scan has fewer valid points than `min_points`.
    TooFewPoints {
        reference: u16,
        current: u16,
        needed: u16,
    },
    /// Too few current points found a partner (scans do not overlap, or the guess is far off).
    TooFewCorrespondences {
        found: u16,
        needed: u16,
    },
    BeamsNotInAngularOrder {
        beam: usize,
    },
    /// The initial guess has a NaN or infinity.
    NonFiniteGuess,
    /// The solution ran away from the guess or stopped being finite.
    Diverged,
    /// The match converged farther from the predicted pose than the vehicle can have moved
    /// since the last scan that matched (refused by the odometry's motion limits).
    Implausible {
        shift_m: f32,
        turn_rad: f32,
    },
}

impl From<PrepareError> for MatchError {
    fn from(e: PrepareError) -> Self {
        match e {
            PrepareError::BeamsNotInAngularOrder { beam } => {
                MatchError::BeamsNotInAngularOrder { beam }
            }
        }
    }
}

impl core::fmt::Display for MatchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MatchError::NoReference => write!(f, "no reference scan yet"),
            MatchError::TooFewPoints {
                reference,
                current,
                needed,
            } => {
                write!(f, "too few valid points (reference {reference}, current {current}, need {needed})")
            }
            MatchError::TooFewCorrespondences { found, needed } => {
                write!(f, "too few correspondences ({found}, need {needed})")
            }
            MatchError::BeamsNotInAngularOrder { beam } => {
                write!(f, "beam {beam} is out of angular order")
            }
            MatchError::NonFiniteGuess => write!(f, "initial guess is not finite"),
            MatchError::Diverged => write!(f, "solution diverged from the initial guess"),
            MatchError::Implausible { shift_m, turn_rad } => write!(
                f,
                "match {shift_m:.3} m and {turn_rad:.3} rad from the prediction, beyond what the motion allows"
            ),
        }
    }
}

impl MatchResult {
    /// The inverse of [`Self::observed_covariance`]: what the match measured, with nothing
    /// along a degenerate direction. There it is assembled from the variance across the
    /// direction and the heading's (the degenerate covariance has no correlation between
    /// them), since that covariance is singular by construction. `None` when the covariance is
    /// not positive definite.
    pub(crate) fn observed_information(&self) -> Option<Sym3> {
        let o = &self.observed_covariance;
        let Some(d) = self.quality.degenerate_direction else {
            return Sym3::from_array(*o).inverse();
        };
        let n = d.perp();
        let var_across = n.x * n.x * o[0][0] + 2.0 * n.x * n.y * o[0][1] + n.y * n.y * o[1][1];
        let var_heading = o[2][2];
        (var_across > 0.0 && var_heading > 0.0).then(|| Sym3 {
            xx: n.x * n.x / var_across,
            xy: n.x * n.y / var_across,
            yy: n.y * n.y / var_across,
            tt: 1.0 / var_heading,
            ..Sym3::default()
        })
    }
}
