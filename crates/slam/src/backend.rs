//! The global half: keyframes as pose-graph nodes, loop closures as edges, optimisation.
//! It never touches the scan path, so it can run beside it on another thread
//! ([`crate::worker`]) without changing what the tracker does.

use crate::config::{EdgeNoise, SlamConfig};
use crate::graph::{
    diagonal_information, Edge, EdgeKind, Information, NodeId, OptimizeConfig, Pose2d, PoseGraph,
};
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
    pub rejections: [usize; 8],
    pub optimisations: usize,
    /// Accepted loops that the graph's robust kernel ignores after the last optimisation.
    pub loops_downweighted: usize,
    /// Keyframes whose scan was dropped because an older keyframe at nearly the same pose
    /// already holds it.
    pub thinned: usize,
    /// Keyframes tied by a direct match to the one `skip_edge_span` before them.
    pub skip_edges: usize,
    /// Beams held by all keyframes (the bulk of the back end's memory).
    pub beams_held: usize,
}

pub struct Backend<const N: usize> {
    config: SlamConfig,
    keyframes: Vec<Keyframe>,
    /// Node `k` is keyframe `k`; the map frame is the first keyframe's tracked pose.
    graph: PoseGraph,
    /// The graph's poses in the onboard type, refreshed after each optimisation.
    poses: Vec<Pose2>,
    optimize: OptimizeConfig,
    /// Loops accepted since the last optimisation, and keyframes added since.
    pending_loops: usize,
    since_optimised: usize,
    /// Whether edges were added since the last optimisation that no loop made pending.
    unoptimised_edges: bool,
    loops: LoopCloser<N>,
    stats: BackendStats,
}

impl<const N: usize> Backend<N> {
    pub fn new(config: SlamConfig) -> Self {
        Self {
            config,
            keyframes: Vec::new(),
            graph: PoseGraph::new(),
            poses: Vec::new(),
            optimize: OptimizeConfig::default(),
            pending_loops: 0,
            since_optimised: 0,
            unoptimised_edges: false,
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

    /// The pose graph (node `k` is keyframe `k`).
    pub fn graph(&self) -> &PoseGraph {
        &self.graph
    }

    /// Adds the next keyframe (tied to the previous one by the tracked motion), searches it
    /// against old submaps, and optimises if a loop was accepted.
    pub fn add_keyframe(&mut self, keyframe: Keyframe) {
        let new = self.keyframes.len();
        let previous = self.keyframes.last().zip(self.poses.last());
        let (pose, motion) = match previous {
            Some((prev, &prev_pose)) => {
                let motion = prev.tracking_pose.between(keyframe.tracking_pose);
                (prev_pose.compose(motion), Some(motion))
            }
            None => (keyframe.tracking_pose, None),
        };
        // Poses come from the tracker and are finite, and the information is a positive
        // diagonal, so the graph cannot refuse them; the node index equals the keyframe's.
        let _ = self.graph.add_node(to_graph(pose));
        if let Some(motion) = motion {
            let _ = self.graph.add_edge(Edge {
                from: node(new - 1),
                to: node(new),
                measurement: to_graph(motion),
                information: odometry_information(&self.config.noise, motion, &keyframe),
                kind: EdgeKind::Odometry,
            });
        }
        self.stats.beams_held += keyframe.beams.len();
        self.keyframes.push(keyframe);
        self.poses.push(pose);
        self.stats.keyframes += 1;
        self.add_skip_edge(new);
        let loops = self.close_loops(new);
        self.pending_loops += loops.len();
        self.since_optimised += 1;
        if self.pending_loops > 0 && self.since_optimised >= self.config.optimise_every_keyframes {
            self.optimise();
        }
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

    /// Optimises what is still pending: call when the log or the flight ends.
    pub fn finish(&mut self) {
        if self.pending_loops > 0 || self.unoptimised_edges {
            self.optimise();
        }
    }

    /// Ties keyframe `new` to the one `skip_edge_span` before it by matching their scans
    /// directly. The tracker's edges chain the two through the keyframes between, each step
    /// with an error of its own; a second path of independent measurements lets the graph
    /// average those errors out instead of keeping every one of them.
    fn add_skip_edge(&mut self, new: usize) {
        let span = self.config.skip_edge_span;
        let Some(old) = new.checked_sub(span).filter(|_| span >= 2) else {
            return;
        };
        let (a, b) = (&self.keyframes[old], &self.keyframes[new]);
        // A predicted keyframe's place is a guess: a match from there is no second opinion.
        if a.predicted || b.predicted || !a.has_scan() || !b.has_scan() {
            return;
        }
        let guess = self.poses[old].between(self.poses[new]);
        let Some(motion) = self.loops.match_pair(&self.keyframes, old, new, guess) else {
            return;
        };
        let edge = Edge {
            from: node(old),
            to: node(new),
            measurement: to_graph(motion),
            information: odometry_information(&self.config.noise, motion, &self.keyframes[new]),
            kind: EdgeKind::Odometry,
        };
        if self.graph.add_edge(edge).is_ok() {
            self.stats.skip_edges += 1;
            self.unoptimised_edges = true;
        }
    }

    /// Searches keyframe `new` against old submaps; returns the accepted loops' measurements.
    fn close_loops(&mut self, new: usize) -> Vec<Pose2> {
        let mut candidates = self.loops.candidates(&self.keyframes, &self.poses, new);
        candidates.truncate(self.loops.budget(&self.keyframes, new));
        let mut accepted = Vec::new();
        for old in candidates {
            self.stats.loop_candidates += 1;
            let guess = self.poses[old].between(self.poses[new]);
            match self
                .loops
                .verify(&self.keyframes, &self.poses, old, new, guess)
            {
                Ok(edge) => {
                    if self
                        .graph
                        .add_edge(loop_edge(&self.config.noise, &edge))
                        .is_ok()
                    {
                        accepted.push(edge.measurement);
                    }
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

    /// Optimises the graph (warm-started from the current poses) and refreshes the poses; loop
    /// edges the robust kernel ends up ignoring are counted as rejected by the graph.
    fn optimise(&mut self) {
        self.pending_loops = 0;
        self.unoptimised_edges = false;
        self.since_optimised = 0;
        let report = self.graph.optimize(&self.optimize);
        self.stats.optimisations += 1;
        self.stats.loops_downweighted = report.downweighted_loops.len();
        for (pose, node) in self.poses.iter_mut().zip(self.graph.nodes()) {
            *pose = Pose2::new(node.x as f32, node.y as f32, node.theta as f32);
        }
    }
}

/// Information of a tracked motion: a floor plus a share of the distance and the turn. A
/// keyframe from a failed match is a prediction: it gets a hundredth of the information.
fn odometry_information(noise: &EdgeNoise, motion: Pose2, keyframe: &Keyframe) -> Information {
    let sigma_m = noise.odometry_m + noise.odometry_per_m * motion.translation().norm();
    let sigma_rad = noise.odometry_rad + noise.odometry_per_rad * motion.theta.abs();
    // A prediction is a guess: ten times the spread, a hundredth of the information.
    let spread = if keyframe.predicted { 10.0 } else { 1.0 };
    diagonal_information(sigma_m as f64 * spread, sigma_rad as f64 * spread)
}

fn loop_edge(noise: &EdgeNoise, edge: &LoopEdge) -> Edge {
    Edge {
        from: node(edge.from),
        to: node(edge.to),
        measurement: to_graph(edge.measurement),
        information: diagonal_information(noise.loop_m as f64, noise.loop_rad as f64),
        kind: EdgeKind::Loop,
    }
}

fn node(index: usize) -> NodeId {
    NodeId(index as u32)
}

fn to_graph(p: Pose2) -> Pose2d {
    Pose2d::new(p.x as f64, p.y as f64, p.theta as f64)
}
