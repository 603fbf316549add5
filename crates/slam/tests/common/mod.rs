//! Synthetic data with known ground truth shared by the integration tests: seeded pose
//! graphs (also used by the graph benchmark, which includes this file by path) and scans of a
//! known room.
//!
//! The vehicle walks a Manhattan world: one metre a step along a grid inside a square box,
//! turning a quarter turn at random or at the box's edge, so it keeps coming back to cells it
//! has visited. Odometry edges carry Gaussian noise; loop edges join a node to an earlier
//! node in the same cell. Initial poses compose the noisy odometry, as a front end would.
#![allow(dead_code)] // each test binary uses a different part

use plumbline_core::geom::Pose2;
use plumbline_core::scan::Beam;
use plumbline_slam::graph::{diagonal_information, Edge, EdgeKind, NodeId, Pose2d, PoseGraph};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::f64::consts::FRAC_PI_2;

pub const ODOM_SIGMA_M: f64 = 0.05;
pub const ODOM_SIGMA_RAD: f64 = 0.01;
pub const LOOP_SIGMA_M: f64 = 0.02;
pub const LOOP_SIGMA_RAD: f64 = 0.005;

pub struct Rng(Xoshiro256PlusPlus);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(Xoshiro256PlusPlus::seed_from_u64(seed))
    }

    pub fn uniform(&mut self) -> f64 {
        self.0.random::<f64>()
    }

    /// Box-Muller: one standard normal draw.
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // in (0, 1], so ln is finite
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    pub fn index(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }

    fn noisy(&mut self, p: Pose2d, sigma_m: f64, sigma_rad: f64) -> Pose2d {
        Pose2d::new(
            p.x + sigma_m * self.normal(),
            p.y + sigma_m * self.normal(),
            p.theta + sigma_rad * self.normal(),
        )
    }
}

/// The true walk: `nodes` poses on a grid of `box_cells` x `box_cells` one-metre cells.
pub fn manhattan_truth(rng: &mut Rng, nodes: usize, box_cells: i32) -> Vec<Pose2d> {
    let mut truth = vec![Pose2d::IDENTITY];
    let (mut cx, mut cy, mut heading) = (0i32, 0i32, 0i32);
    while truth.len() < nodes {
        if rng.uniform() < 0.2 {
            heading += if rng.uniform() < 0.5 { 1 } else { -1 };
        }
        let step = |h: i32| match h.rem_euclid(4) {
            0 => (1, 0),
            1 => (0, 1),
            2 => (-1, 0),
            _ => (0, -1),
        };
        let inside = |h: i32| {
            let (dx, dy) = step(h);
            (0..box_cells).contains(&(cx + dx)) && (0..box_cells).contains(&(cy + dy))
        };
        while !inside(heading) {
            heading += 1;
        }
        let (dx, dy) = step(heading);
        (cx, cy) = (cx + dx, cy + dy);
        truth.push(Pose2d::new(
            cx as f64,
            cy as f64,
            f64::from(heading) * FRAC_PI_2,
        ));
    }
    truth
}

/// Pairs (earlier, later) of nodes in the same cell, at least 10 steps apart, later node
/// ascending, at most one per later node; `max_loops` of them spread evenly over the walk.
pub fn loop_pairs(truth: &[Pose2d], max_loops: usize) -> Vec<(usize, usize)> {
    let mut all = Vec::new();
    for j in 0..truth.len() {
        let same = (0..j.saturating_sub(10)).find(|&i| {
            (truth[i].x - truth[j].x).abs() < 0.5 && (truth[i].y - truth[j].y).abs() < 0.5
        });
        if let Some(i) = same {
            all.push((i, j));
        }
    }
    if all.len() <= max_loops {
        return all;
    }
    (0..max_loops)
        .map(|k| all[k * all.len() / max_loops])
        .collect()
}

pub fn odometry_edge(rng: &mut Rng, truth: &[Pose2d], i: usize) -> Edge {
    Edge {
        from: NodeId(i as u32),
        to: NodeId(i as u32 + 1),
        measurement: rng.noisy(truth[i].between(truth[i + 1]), ODOM_SIGMA_M, ODOM_SIGMA_RAD),
        information: diagonal_information(ODOM_SIGMA_M, ODOM_SIGMA_RAD),
        kind: EdgeKind::Odometry,
    }
}

pub fn loop_edge(rng: &mut Rng, truth: &[Pose2d], i: usize, j: usize) -> Edge {
    Edge {
        from: NodeId(i as u32),
        to: NodeId(j as u32),
        measurement: rng.noisy(truth[i].between(truth[j]), LOOP_SIGMA_M, LOOP_SIGMA_RAD),
        information: diagonal_information(LOOP_SIGMA_M, LOOP_SIGMA_RAD),
        kind: EdgeKind::Loop,
    }
}

/// A wrong loop claiming that node `j` sits where node `k` is, seen from node `i`.
pub fn false_loop_edge(truth: &[Pose2d], i: usize, j: usize, k: usize) -> Edge {
    Edge {
        from: NodeId(i as u32),
        to: NodeId(j as u32),
        measurement: truth[i].between(truth[k]),
        information: diagonal_information(LOOP_SIGMA_M, LOOP_SIGMA_RAD),
        kind: EdgeKind::Loop,
    }
}

/// The odometry chain alone: nodes placed by composing the noisy odometry from the origin.
pub fn odometry_graph(rng: &mut Rng, truth: &[Pose2d]) -> PoseGraph {
    let mut graph = PoseGraph::new();
    let mut pose = truth[0];
    graph.add_node(pose).unwrap();
    for i in 0..truth.len() - 1 {
        let edge = odometry_edge(rng, truth, i);
        pose = pose.compose(edge.measurement);
        graph.add_node(pose).unwrap();
        graph.add_edge(edge).unwrap();
    }
    graph
}

/// Root-mean-square position error of the graph's nodes against the truth (both start at the
/// fixed first node, so no alignment is needed).
pub fn rms_error_m(graph: &PoseGraph, truth: &[Pose2d]) -> f64 {
    let sum: f64 = (graph.nodes().iter().zip(truth))
        .map(|(p, t)| (p.x - t.x).powi(2) + (p.y - t.y).powi(2))
        .sum();
    (sum / truth.len() as f64).sqrt()
}

/// A 2,000-node walk with 50 loops, optimised, plus one more correct loop to add: the state
/// the front end is in when it accepts a loop closure. Used by the benchmark.
pub fn bench_graph(seed: u64, nodes: usize, loops: usize) -> (PoseGraph, Vec<Pose2d>, Vec<Edge>) {
    let mut rng = Rng::new(seed);
    let truth = manhattan_truth(&mut rng, nodes, 15);
    let graph = odometry_graph(&mut rng, &truth);
    let edges = loop_pairs(&truth, loops)
        .into_iter()
        .map(|(i, j)| loop_edge(&mut rng, &truth, i, j))
        .collect();
    (graph, truth, edges)
}

/// Beams from `pose` to the walls of the axis-aligned room [0, w] x [0, h] (exact ranges),
/// evenly spread over the full turn.
pub fn room_scan(pose: Pose2, w: f32, h: f32, beams: usize) -> Vec<Beam> {
    (0..beams)
        .map(|k| {
            let a = k as f32 * core::f32::consts::TAU / beams as f32 - core::f32::consts::PI;
            let (dx, dy) = ((pose.theta + a).cos(), (pose.theta + a).sin());
            let tx = if dx > 0.0 {
                (w - pose.x) / dx
            } else {
                -pose.x / dx
            };
            let ty = if dy > 0.0 {
                (h - pose.y) / dy
            } else {
                -pose.y / dy
            };
            Beam::new(a, tx.min(ty))
        })
        .collect()
}
