//! The global half: keyframes as pose-graph nodes, loop closures as edges, optimisation.
//! It never touches the scan path, so it can run beside it on another thread
//! ([`crate::worker`]) without changing what the tracker does.

use crate::config::{EdgeNoise, SlamConfig};
use crate::keyframe::Keyframe;
use crate::loops::{LoopCloser, LoopEdge};
use plumbline_core::geom::Pose2;

/// Counts for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BackendStats {
    pub keyframes: usize,
    pub loop_candidates: usize,
    pub loops_accepted: usize,
    pub loops_rejected: usize,
    /// Rejected loop candidates by [`crate::loops::Rejection`] reason.
    pub rejections: [usize; 6],
    pub optimisations: usize,
    /// Keyframes whose scan was dropped because an older keyframe at nearly the same pose
    /// already holds it.
    pub thinned: usize,
    /// Beams held by all keyframes (the bulk of the back end's memory).
    pub beams_held: usize,
}

/// An edge of the pose graph: the pose of `to` in the frame of `from`, with its information.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraphEdge {
    pub from: usize,
    pub to: usize,
    pub measurement: Pose2,
    pub information: [[f64; 3]; 3],
    pub is_loop: bool,
}

pub struct Backend<const N: usize> {
    config: SlamConfig,
    keyframes: Vec<Keyframe>,
    /// Graph poses of the keyframes (map frame: the first keyframe's).
    poses: Vec<Pose2>,
    edges: Vec<GraphEdge>,
    loops: LoopCloser<N>,
    stats: BackendStats,
}

impl<const N: usize> Backend<N> {
    pub fn new(config: SlamConfig) -> Self {
        Self {
            config,
            keyframes: Vec::new(),
            poses: Vec::new(),
            edges: Vec::new(),
            loops: LoopCloser::new(config.loops),
            stats: BackendStats::default(),
        }
    }

    pub fn stats(&self) -> BackendStats {
        self.stats
    }

    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// Graph poses of the keyframes, in the map frame.
    pub fn poses(&self) -> &[Pose2] {
        &self.poses
    }

    pub fn edges(&self) -> &[GraphEdge] {
        &self.edges
    }

    /// Adds the next keyframe (tied to the previous one by the tracked motion), searches it
    /// against old submaps, and optimises if a loop was accepted.
    pub fn add_keyframe(&mut self, keyframe: Keyframe) {
        let new = self.keyframes.len();
        let pose = match (self.keyframes.last(), self.poses.last()) {
            (Some(prev), Some(&prev_pose)) => {
                let motion = prev.tracking_pose.between(keyframe.tracking_pose);
                self.edges.push(GraphEdge {
                    from: new - 1,
                    to: new,
                    measurement: motion,
                    information: odometry_information(&self.config.noise, motion, &keyframe),
                    is_loop: false,
                });
                prev_pose.compose(motion)
            }
            _ => keyframe.tracking_pose,
        };
        self.stats.beams_held += keyframe.beams.len();
        self.keyframes.push(keyframe);
        self.poses.push(pose);
        self.stats.keyframes += 1;
        let loops = self.close_loops(new);
        if loops.is_empty() {
            return;
        }
        self.optimise();
        let cfg = &self.config;
        let redundant = loops.iter().any(|m| {
            m.translation().norm() < cfg.thin_distance_m && m.theta.abs() < cfg.thin_angle_rad
        });
        if redundant {
            self.stats.beams_held -= self.keyframes[new].beams.len();
            self.keyframes[new].drop_scan();
            self.stats.thinned += 1;
        }
    }

    /// Searches keyframe `new` against old submaps; returns the accepted loops' measurements.
    fn close_loops(&mut self, new: usize) -> Vec<Pose2> {
        let candidates = self.loops.candidates(&self.keyframes, &self.poses, new);
        let mut accepted = Vec::new();
        for old in candidates {
            self.stats.loop_candidates += 1;
            let guess = self.poses[old].between(self.poses[new]);
            match self
                .loops
                .verify(&self.keyframes, &self.poses, old, new, guess)
            {
                Ok(edge) => {
                    self.edges.push(loop_edge(&self.config.noise, &edge));
                    accepted.push(edge.measurement);
                }
                Err(r) => {
                    self.stats.loops_rejected += 1;
                    self.stats.rejections[r as usize] += 1;
                }
            }
        }
        self.stats.loops_accepted += accepted.len();
        accepted
    }

    fn optimise(&mut self) {
        self.stats.optimisations += 1;
    }
}

/// Information of a tracked motion: a floor plus a share of the distance and the turn. A
/// keyframe from a failed match is a prediction: it gets a hundredth of the information.
fn odometry_information(noise: &EdgeNoise, motion: Pose2, keyframe: &Keyframe) -> [[f64; 3]; 3] {
    let sigma_m = noise.odometry_m + noise.odometry_per_m * motion.translation().norm();
    let sigma_rad = noise.odometry_rad + noise.odometry_per_rad * motion.theta.abs();
    let scale = if keyframe.predicted { 0.01 } else { 1.0 };
    diagonal(sigma_m, sigma_rad, scale)
}

fn loop_edge(noise: &EdgeNoise, edge: &LoopEdge) -> GraphEdge {
    GraphEdge {
        from: edge.from,
        to: edge.to,
        measurement: edge.measurement,
        information: diagonal(noise.loop_m, noise.loop_rad, 1.0),
        is_loop: true,
    }
}

fn diagonal(sigma_m: f32, sigma_rad: f32, scale: f64) -> [[f64; 3]; 3] {
    let im = scale / (sigma_m as f64 * sigma_m as f64);
    let ir = scale / (sigma_rad as f64 * sigma_rad as f64);
    [[im, 0.0, 0.0], [0.0, im, 0.0], [0.0, 0.0, ir]]
}
