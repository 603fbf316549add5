//! Lidar-only odometry: chains scan matches into a pose, the way the vehicle uses it in flight.
//!
//! Each scan is matched against a keyframe rather than the scan just before it, so while the
//! vehicle stays near a keyframe its error does not grow scan by scan; a new keyframe is taken
//! once the vehicle has moved far enough that overlap starts to suffer. The initial guess is a
//! caller's prior (wheel odometry, IMU) or, lidar-only, the last motion repeated.

use super::{MatchConfig, MatchError, MatchResult, ScanMatcher};
use crate::geom::{Pose2, Vec2};
use crate::scan::Scan;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryConfig {
    pub matcher: MatchConfig,
    /// Take a new keyframe after moving this far from the current one, m.
    pub keyframe_distance_m: f32,
    /// …or turning this much, rad.
    pub keyframe_angle_rad: f32,
    /// …or when fewer than this fraction of points still find a partner in it.
    pub keyframe_min_inlier_ratio: f32,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            matcher: MatchConfig::default(),
            keyframe_distance_m: 0.3,
            keyframe_angle_rad: 0.25,
            keyframe_min_inlier_ratio: 0.6,
        }
    }
}

/// What one scan did to the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OdometryStep {
    /// The first usable scan: it became the first keyframe at the origin.
    Started,
    /// Matched; the pose is updated from the match.
    Matched {
        result: MatchResult,
        new_keyframe: bool,
    },
    /// The match failed; the pose was carried forward by the prediction alone.
    Predicted {
        error: MatchError,
        /// This scan became the keyframe, so one bad keyframe cannot stall the odometry; it
        /// does not when the scan itself was unusable.
        restarted: bool,
    },
}

impl OdometryStep {
    /// Whether this scan became the keyframe the next scans are matched against.
    pub fn took_keyframe(&self) -> bool {
        match *self {
            Self::Started => true,
            Self::Matched { new_keyframe, .. } => new_keyframe,
            Self::Predicted { restarted, .. } => restarted,
        }
    }
}

#[derive(Clone, Debug)]
pub struct LidarOdometry<const N: usize> {
    config: OdometryConfig,
    matcher: ScanMatcher<N>,
    keyframe_pose: Pose2,
    pose: Pose2,
    /// Motion over the last scan interval, the lidar-only prediction for the next one.
    last_motion: Pose2,
    keyframes_taken: u32,
}

impl<const N: usize> LidarOdometry<N> {
    pub fn new(config: OdometryConfig) -> Self {
        Self {
            config,
            matcher: ScanMatcher::new(config.matcher),
            keyframe_pose: Pose2::IDENTITY,
            pose: Pose2::IDENTITY,
            last_motion: Pose2::IDENTITY,
            keyframes_taken: 0,
        }
    }

    /// Pose of the current keyframe in the frame of the first scan.
    pub fn keyframe_pose(&self) -> Pose2 {
        self.keyframe_pose
    }

    /// How many keyframes have been taken so far: a clock that ticks once a keyframe, by which
    /// the local map tells old walls from new.
    pub fn keyframes_taken(&self) -> u32 {
        self.keyframes_taken
    }

    /// The current keyframe's points in its own frame.
    pub fn keyframe_points(&self) -> &[Vec2] {
        self.matcher.reference_points()
    }

    /// Moves the keyframe just taken (and so the current pose) to where another source, such as
    /// a map, places it better. Call it only right after an update that took a keyframe.
    pub fn reanchor_keyframe(&mut self, pose: Pose2) {
        self.keyframe_pose = pose;
        self.pose = pose;
    }

    /// Current pose estimate in the frame of the first scan.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Feeds the next revolution; `prior` is the motion since the previous scan from another
    /// source, if there is one.
    pub fn update(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> OdometryStep {
        if !self.matcher.has_reference() {
            return match self.matcher.set_reference(scan) {
                Ok(()) => {
                    self.keyframe_pose = self.pose;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                    OdometryStep::Started
                }
                Err(error) => OdometryStep::Predicted {
                    error,
                    restarted: false,
                },
            };
        }
        let predicted_motion = prior.filter(|p| p.is_finite()).unwrap_or(self.last_motion);
        let predicted = self.pose.compose(predicted_motion);
        let guess = self.keyframe_pose.between(predicted);
        match self.matcher.match_scan(scan, guess) {
            Ok(result) => {
                let new_pose = self.keyframe_pose.compose(result.motion);
                self.last_motion = self.pose.between(new_pose);
                self.pose = new_pose;
                let (dist, angle) = self.keyframe_pose.distance_to(new_pose);
                let new_keyframe = dist > self.config.keyframe_distance_m
                    || angle > self.config.keyframe_angle_rad
                    || result.quality.inlier_ratio < self.config.keyframe_min_inlier_ratio;
                if new_keyframe {
                    self.matcher.promote_current();
                    self.keyframe_pose = new_pose;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                }
                OdometryStep::Matched {
                    result,
                    new_keyframe,
                }
            }
            Err(error) => {
                self.pose = predicted;
                let restarted = !matches!(
                    error,
                    MatchError::TooFewPoints { .. } | MatchError::BeamsNotInAngularOrder { .. }
                ) && self.matcher.set_reference(scan).is_ok();
                if restarted {
                    self.keyframe_pose = predicted;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                }
                OdometryStep::Predicted { error, restarted }
            }
        }
    }
}
