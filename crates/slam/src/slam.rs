//! The SLAM driver: one call per scan, online or over a log.
//!
//! Tracking is Plumbline's odometry with its rolling local map (scan-to-keyframe ICL, every
//! keyframe aligned with the walls seen lately). Each keyframe becomes a pose-graph node tied
//! to the previous one by the tracked motion; keyframes are grouped into submaps, and every new
//! keyframe is checked against frozen submaps nearby for a loop. A verified loop adds an edge and
//! the graph is optimised, which moves every keyframe, and with it every scan, since a scan's
//! pose is its keyframe's graph pose composed with the tracked motion from that keyframe.

use crate::config::SlamConfig;
use crate::keyframe::Keyframe;
use crate::loops::LoopCloser;
use plumbline_core::geom::Pose2;
use plumbline_core::matching::local_map::{LineMap, MapCell, MapUse, MappedOdometry};
use plumbline_core::matching::OdometryStep;
use plumbline_core::scan::Scan;

/// Where one scan ended up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPose {
    /// The keyframe the scan is anchored to (`None` before the first usable scan).
    pub keyframe: Option<usize>,
    /// The scan's pose in the frame of that keyframe.
    pub relative: Pose2,
    /// The scan's pose in the map frame as known now (later loop closures may move it).
    pub pose: Pose2,
    pub new_keyframe: bool,
    /// The match failed and the pose is a prediction.
    pub predicted: bool,
    pub loops_accepted: usize,
}

/// Counts for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlamStats {
    pub scans: usize,
    pub predicted_scans: usize,
    pub loop_candidates: usize,
    pub loops_accepted: usize,
    pub loops_rejected: usize,
    pub optimisations: usize,
    /// Rejected loop candidates by [`Rejection`] reason.
    pub rejections: [usize; 6],
}

/// Cells the rolling local map needs for `config` (the caller owns them, as in the onboard code).
pub fn local_map_cells(config: &SlamConfig) -> Vec<MapCell> {
    let side = (config.local_map_size_m / config.local_map.cell_m)
        .ceil()
        .max(1.0) as usize;
    vec![MapCell::default(); side * side]
}

pub struct Slam<'m, const N: usize> {
    config: SlamConfig,
    tracker: Box<MappedOdometry<'m, N>>,
    keyframes: Vec<Keyframe>,
    /// Graph poses of the keyframes (map frame).
    poses: Vec<Pose2>,
    loops: LoopCloser<N>,
    stats: SlamStats,
}

/// The local map could not be made from the configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError(pub String);

impl<'m, const N: usize> Slam<'m, N> {
    pub fn new(config: SlamConfig, cells: &'m mut [MapCell]) -> Result<Self, ConfigError> {
        let map = LineMap::new(cells, config.local_map)
            .map_err(|e| ConfigError(format!("local map: {e:?}")))?;
        Ok(Self {
            config,
            tracker: Box::new(MappedOdometry::new(
                config.odometry,
                map,
                config.refine,
                None,
            )),
            keyframes: Vec::new(),
            poses: Vec::new(),
            loops: LoopCloser::new(config.loops),
            stats: SlamStats::default(),
        })
    }

    pub fn stats(&self) -> SlamStats {
        self.stats
    }

    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// Graph poses of the keyframes, in the map frame.
    pub fn keyframe_poses(&self) -> &[Pose2] {
        &self.poses
    }

    /// The map-frame pose of a scan anchored at `keyframe` with `relative` motion, as of now.
    pub fn pose_of(&self, keyframe: usize, relative: Pose2) -> Pose2 {
        self.poses[keyframe].compose(relative)
    }

    /// Feeds the next revolution; `prior` is the motion since the previous scan from another
    /// source (wheel odometry), if any.
    pub fn add_scan(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> ScanPose {
        self.stats.scans += 1;
        let step = self.tracker.update(scan, prior);
        let tracked = self.tracker.pose();
        let predicted = matches!(step.step, OdometryStep::Predicted { .. });
        self.stats.predicted_scans += predicted as usize;
        let new_keyframe = !matches!(step.map, MapUse::NotKeyframe);
        let mut loops_accepted = 0;
        if new_keyframe {
            self.add_keyframe(scan, tracked, matches!(step.map, MapUse::Skipped));
            loops_accepted = self.close_loops();
        }
        let Some(anchor) = self.keyframes.len().checked_sub(1) else {
            return ScanPose {
                keyframe: None,
                relative: Pose2::IDENTITY,
                pose: tracked,
                new_keyframe: false,
                predicted,
                loops_accepted: 0,
            };
        };
        let relative = self.keyframes[anchor].tracking_pose.between(tracked);
        ScanPose {
            keyframe: Some(anchor),
            relative,
            pose: self.pose_of(anchor, relative),
            new_keyframe,
            predicted,
            loops_accepted,
        }
    }

    fn add_keyframe(&mut self, scan: &Scan<N>, tracked: Pose2, predicted: bool) {
        let per_submap = self.config.keyframes_per_submap.max(1);
        let submap = self.keyframes.len() / per_submap;
        let (pose, path_m) = match (self.keyframes.last(), self.poses.last()) {
            (Some(prev), Some(&prev_pose)) => {
                let motion = prev.tracking_pose.between(tracked);
                (
                    prev_pose.compose(motion),
                    prev.path_m + motion.translation().norm(),
                )
            }
            _ => (tracked, 0.0),
        };
        self.keyframes
            .push(Keyframe::new(scan, tracked, submap, path_m, predicted));
        self.poses.push(pose);
    }

    /// Searches the newest keyframe against old submaps; returns how many loops were accepted.
    fn close_loops(&mut self) -> usize {
        let new = self.keyframes.len() - 1;
        let candidates = self.loops.candidates(&self.keyframes, &self.poses, new);
        let mut accepted = 0;
        for old in candidates {
            self.stats.loop_candidates += 1;
            let guess = self.poses[old].between(self.poses[new]);
            match self
                .loops
                .verify(&self.keyframes, &self.poses, old, new, guess)
            {
                Ok(_edge) => accepted += 1,
                Err(r) => {
                    self.stats.loops_rejected += 1;
                    self.stats.rejections[r as usize] += 1;
                }
            }
        }
        self.stats.loops_accepted += accepted;
        accepted
    }
}
