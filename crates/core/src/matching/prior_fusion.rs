//! Combining a scan match with a motion prior by their covariances.
//!
//! A match measures the scan's pose relative to its keyframe well across walls and in heading,
//! and nothing along a featureless corridor's axis; a motion prior (wheel odometry, an IMU)
//! measures every direction a little. Taking the match whole and the prior only as its starting
//! guess throws the prior away exactly where it is the only measurement, and lets the match's
//! own noise (a few tenths of a degree a scan in heading with a short-range lidar) add up scan
//! by scan even when the prior is far better. So the two are combined as a Kalman filter over
//! the pose relative to the current keyframe: the prior predicts it with a variance that grows
//! scan by scan from the keyframe, the match updates it with its information, and along a
//! direction the match did not observe the prior's value stands. A new keyframe is the new
//! reference, so the relative pose and its variance start again from zero there.

use super::linalg::Sym3;
use super::MatchResult;
use crate::geom::{normalize_angle, Pose2};

/// How much a caller's prior and the scan match are trusted, for [`fuse`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PriorFusion {
    /// The prior's error over one scan interval, one standard deviation per axis of
    /// translation: a floor plus a share of the distance moved, m and m/m…
    pub floor_m: f32,
    pub per_m: f32,
    /// …and in heading: a floor plus a share of the turn, rad and rad/rad.
    pub floor_rad: f32,
    pub per_rad: f32,
    /// Scale on the match's covariance. It is the residual variance times the inverse
    /// information, as if every point's error were independent, and it is that much too
    /// confident: neighbouring points of one wall share its error.
    pub match_covariance_scale: f32,
}

impl PriorFusion {
    /// The match's covariance is taken [`Self::MATCH_COVARIANCE_SCALE`] times too confident, as
    /// the pose graph's and the local map's weights take it (about a hundred times).
    pub const MATCH_COVARIANCE_SCALE: f32 = 100.0;

    /// A prior of the given spread per scan interval, against the match's covariance scaled
    /// by [`Self::MATCH_COVARIANCE_SCALE`].
    pub fn new(floor_m: f32, per_m: f32, floor_rad: f32, per_rad: f32) -> Self {
        Self {
            floor_m,
            per_m,
            floor_rad,
            per_rad,
            match_covariance_scale: Self::MATCH_COVARIANCE_SCALE,
        }
    }

    /// The prior's covariance for one step of `motion` (isotropic in translation, so it is the
    /// same in any frame).
    fn step_covariance(&self, motion: Pose2) -> Sym3 {
        let sm = self.floor_m + self.per_m * motion.translation().norm();
        let sr = self.floor_rad + self.per_rad * motion.theta.abs();
        Sym3 {
            xx: sm * sm,
            yy: sm * sm,
            tt: sr * sr,
            ..Sym3::default()
        }
    }
}

/// The pose relative to the keyframe predicted by the prior: `from` (the last pose relative to
/// the keyframe, covariance `covariance`) moved by `motion`, and its covariance.
pub fn predict(config: &PriorFusion, from: Pose2, covariance: &Sym3, motion: Pose2) -> Sym3 {
    // Jacobian of from ∘ motion with respect to `from`; the step's own noise is isotropic in
    // translation, so turning it into the keyframe's axes leaves it as it is.
    let (s, c) = (libm::sinf(from.theta), libm::cosf(from.theta));
    let j = [
        [1.0, 0.0, -s * motion.x - c * motion.y],
        [0.0, 1.0, c * motion.x - s * motion.y],
        [0.0, 0.0, 1.0],
    ];
    congruence(&j, covariance).plus(&config.step_covariance(motion))
}

/// The match `result` (the scan's pose relative to the keyframe) combined with the prediction
/// `predicted` of covariance `covariance`: the combined pose and its covariance, or `None`
/// when either information cannot be formed (the caller then keeps the match as it is).
pub fn fuse(
    config: &PriorFusion,
    predicted: Pose2,
    covariance: &Sym3,
    result: &MatchResult,
) -> Option<(Pose2, Sym3)> {
    let prior = covariance.inverse()?;
    let scale = config.match_covariance_scale;
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let measured = result.observed_information()?.scaled(1.0 / scale);
    let total = prior.plus(&measured);
    let combined = total.inverse()?;
    let z = result.motion;
    let innovation = [
        z.x - predicted.x,
        z.y - predicted.y,
        normalize_angle(z.theta - predicted.theta),
    ];
    let step = combined.mul(measured.mul(innovation));
    let pose = Pose2::new(
        predicted.x + step[0],
        predicted.y + step[1],
        normalize_angle(predicted.theta + step[2]),
    );
    pose.is_finite().then_some((pose, combined))
}

/// `J M Jᵀ` for a symmetric `M`.
fn congruence(j: &[[f32; 3]; 3], m: &Sym3) -> Sym3 {
    let m = m.to_array();
    let jm: [[f32; 3]; 3] =
        core::array::from_fn(|r| core::array::from_fn(|c| (0..3).map(|k| j[r][k] * m[k][c]).sum()));
    let e = |r: usize, c: usize| -> f32 { (0..3).map(|k| jm[r][k] * j[c][k]).sum() };
    Sym3 {
        xx: e(0, 0),
        xy: e(0, 1),
        xt: e(0, 2),
        yy: e(1, 1),
        yt: e(1, 2),
        tt: e(2, 2),
    }
}
