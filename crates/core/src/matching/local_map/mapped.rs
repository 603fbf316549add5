//! Odometry with a local map: scan-to-keyframe matching as before, and every new keyframe
//! aligned with the map before it is added to it.

use super::cells::LineMap;
use super::refine::{refine, RefineConfig, RefineRefusal, Refined};
use crate::geom::Pose2;
use crate::matching::linalg::Sym3;
use crate::matching::{LidarOdometry, MatchResult, OdometryConfig, OdometryStep};
use crate::scan::Scan;

/// What the map did with one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapUse {
    /// Not a keyframe: the pose is the scan matcher's.
    NotKeyframe,
    /// The keyframe was aligned with the map, then added to it.
    Refined(Refined),
    /// The map could not align the keyframe; it was added at the scan matcher's pose.
    Refused(RefineRefusal),
    /// The keyframe came from a failed match (a guess), so it was neither aligned nor added.
    Skipped,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MappedStep {
    pub step: OdometryStep,
    pub map: MapUse,
}

pub struct MappedOdometry<'m, const N: usize> {
    odometry: LidarOdometry<N>,
    map: LineMap<'m>,
    refine: RefineConfig,
}

impl<'m, const N: usize> MappedOdometry<'m, N> {
    pub fn new(config: OdometryConfig, map: LineMap<'m>, refine: RefineConfig) -> Self {
        Self {
            odometry: LidarOdometry::new(config),
            map,
            refine,
        }
    }

    pub fn pose(&self) -> Pose2 {
        self.odometry.pose()
    }

    pub fn map(&self) -> &LineMap<'m> {
        &self.map
    }

    pub fn update(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> MappedStep {
        let keyframes_before = self.odometry.keyframes_taken();
        let previous_keyframe = self.odometry.keyframe_pose();
        let step = self.odometry.update(scan, prior);
        if self.odometry.keyframes_taken() == keyframes_before {
            return MappedStep {
                step,
                map: MapUse::NotKeyframe,
            };
        }
        let map = match step {
            OdometryStep::Started => {
                self.add_keyframe();
                MapUse::Refined(Refined {
                    pose: self.odometry.pose(),
                    matched: 0,
                    iterations: 0,
                })
            }
            OdometryStep::Matched { result, .. } => self.align_keyframe(&result, previous_keyframe),
            OdometryStep::Predicted { .. } => MapUse::Skipped,
        };
        MappedStep { step, map }
    }

    fn align_keyframe(&mut self, result: &MatchResult, previous_keyframe: Pose2) -> MapUse {
        let Some(information) = information_in_world(
            &result.covariance,
            self.refine.matcher_weight,
            previous_keyframe.theta,
        ) else {
            return MapUse::Refused(RefineRefusal::Diverged);
        };
        let outcome = refine(
            &self.map,
            self.odometry.keyframe_points(),
            self.odometry.pose(),
            information,
            &self.refine,
        );
        if let Ok(refined) = outcome {
            self.odometry.reanchor_keyframe(refined.pose);
        }
        self.add_keyframe();
        match outcome {
            Ok(refined) => MapUse::Refined(refined),
            Err(refusal) => MapUse::Refused(refusal),
        }
    }

    fn add_keyframe(&mut self) {
        let pose = self.odometry.pose();
        for &p in self.odometry.keyframe_points() {
            self.map.insert(pose.transform(p));
        }
    }
}

/// The scan matcher's information (inverse covariance of the motion in the previous keyframe's
/// frame) re-expressed for a world-frame pose: `B Λ Bᵀ` with `B = diag(R(heading), 1)`.
fn information_in_world(covariance: &[[f32; 3]; 3], weight: f32, heading: f32) -> Option<Sym3> {
    let m = Sym3 {
        xx: covariance[0][0],
        xy: covariance[0][1],
        xt: covariance[0][2],
        yy: covariance[1][1],
        yt: covariance[1][2],
        tt: covariance[2][2],
    }
    .inverse()?;
    let (s, c) = (libm::sinf(heading), libm::cosf(heading));
    Some(Sym3 {
        xx: weight * (c * c * m.xx - 2.0 * c * s * m.xy + s * s * m.yy),
        xy: weight * (c * s * (m.xx - m.yy) + (c * c - s * s) * m.xy),
        yy: weight * (s * s * m.xx + 2.0 * c * s * m.xy + c * c * m.yy),
        xt: weight * (c * m.xt - s * m.yt),
        yt: weight * (s * m.xt + c * m.yt),
        tt: weight * m.tt,
    })
}
