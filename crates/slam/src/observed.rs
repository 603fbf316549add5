//! What one scan's match observed: the covariance of its pose relative to its keyframe and the
//! direction it could not see, turned from the keyframe's axes into another frame's.
//!
//! The scan matcher ([`plumbline_core::matching`]) already derives both from the matched
//! geometry: the covariance is the residual variance times the inverse of the Gauss-Newton
//! information of the point-to-line residuals at the solution. A translation direction whose
//! line information (rotation left free) is below `MatchConfig::degenerate_ratio` of the
//! best-constrained direction's is measured instead by the ends of walls both scans see (door
//! frames, openings), with a variance from their beam spacing; only where too few agree is it
//! reported degenerate, with [`plumbline_core::matching::UNOBSERVED_VARIANCE`] along it: the
//! pose there is the motion guess, not a measurement. Nothing here changes the estimate; it
//! only reports.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::matching::MatchResult;

/// The match of one scan against its keyframe, in the axes of some frame (see where it is
/// returned for which).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observed {
    /// Covariance of (x, y, heading) in m², m·rad and rad²; row-major, symmetric. It is what
    /// this scan's match measured relative to its keyframe; the keyframe's own uncertainty in
    /// the map is not in it.
    pub covariance: [[f32; 3]; 3],
    /// The same with no variance along the degenerate direction (only what the match saw;
    /// `MatchResult::observed_covariance`), for a consumer that sets its own variance there.
    pub seen_covariance: [[f32; 3]; 3],
    /// Unit direction along which the match saw nothing (a featureless corridor's axis); the
    /// variance along it is unobserved. `None` when both directions are constrained.
    pub degenerate_direction: Option<Vec2>,
    /// Share of the scan's valid points that found a partner in the keyframe (0 to 1): how
    /// much of what the lidar saw the match explained.
    pub inlier_ratio: f32,
}

impl Observed {
    /// The match's report, in the axes of its reference (keyframe) scan.
    pub fn from_match(result: &MatchResult) -> Self {
        Self {
            covariance: result.covariance,
            seen_covariance: result.observed_covariance,
            degenerate_direction: result.quality.degenerate_direction,
            inlier_ratio: result.quality.inlier_ratio,
        }
    }

    /// The same, with its axes turned by `angle_rad`: `B Σ Bᵀ` with `B = diag(R(angle), 1)`.
    pub fn rotated(&self, angle_rad: f32) -> Self {
        let turn = Pose2::new(0.0, 0.0, angle_rad);
        Self {
            covariance: rotate_covariance(&self.covariance, angle_rad),
            seen_covariance: rotate_covariance(&self.seen_covariance, angle_rad),
            degenerate_direction: self.degenerate_direction.map(|d| turn.rotate(d)),
            inlier_ratio: self.inlier_ratio,
        }
    }

    /// Variance of the position along the unit direction `u`, m².
    pub fn variance_along(&self, u: Vec2) -> f32 {
        let m = &self.covariance;
        u.x * u.x * m[0][0] + 2.0 * u.x * u.y * m[0][1] + u.y * u.y * m[1][1]
    }
}

/// `B Σ Bᵀ` with `B = diag(R(angle), 1)`: a covariance of (x, y, heading) in turned axes.
fn rotate_covariance(m: &[[f32; 3]; 3], angle_rad: f32) -> [[f32; 3]; 3] {
    let (s, c) = angle_rad.sin_cos();
    let b = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
    let bm: [[f32; 3]; 3] =
        core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| b[i][k] * m[k][j]).sum()));
    // One triangle, mirrored, so the result is exactly symmetric.
    let entry = |i: usize, j: usize| -> f32 {
        let (i, j) = (i.min(j), i.max(j));
        (0..3).map(|k| bm[i][k] * b[j][k]).sum()
    };
    core::array::from_fn(|i| core::array::from_fn(|j| entry(i, j)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_the_axes_turns_the_variances_and_the_direction_and_keeps_the_heading() {
        // 1 cm across x, 1 m along y, a degenerate y, heading variance with no correlation.
        let o = Observed {
            covariance: [[1e-4, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 4e-6]],
            seen_covariance: [[1e-4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 4e-6]],
            degenerate_direction: Some(Vec2::new(0.0, 1.0)),
            inlier_ratio: 0.9,
        };
        let q = core::f32::consts::FRAC_PI_2;
        let t = o.rotated(q);
        // A quarter turn: y's variance is now x's.
        assert!((t.covariance[0][0] - 1.0).abs() < 1e-6, "{t:?}");
        assert!((t.covariance[1][1] - 1e-4).abs() < 1e-6, "{t:?}");
        assert!(t.covariance[2][2] == 4e-6);
        let d = t.degenerate_direction.unwrap();
        assert!((d.x + 1.0).abs() < 1e-6 && d.y.abs() < 1e-6, "{d:?}");
        // At 0.6 rad the variance along the turned direction is the original's along y.
        let a = 0.6;
        let t = o.rotated(a);
        let along = t.degenerate_direction.unwrap();
        assert!((t.variance_along(along) - 1.0).abs() < 1e-5);
        assert!((t.variance_along(along.perp()) - 1e-4).abs() < 1e-5);
        assert_eq!(t.covariance[0][1], t.covariance[1][0]);
        // The seen part turns the same way and stays blind along the direction.
        assert!(t.seen_covariance == rotate_covariance(&o.seen_covariance, a));
        assert!(t.variance_along(along) > 0.99);
        let seen = Observed {
            covariance: t.seen_covariance,
            ..t
        };
        assert!(seen.variance_along(along).abs() < 1e-6);
        assert_eq!(t.inlier_ratio, 0.9);
    }
}
