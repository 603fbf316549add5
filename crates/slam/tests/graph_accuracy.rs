//! The optimiser against ground truth on seeded synthetic walks: loops must pull a drifting
//! odometry chain back to the truth, and false loops must not bend it while the kernel is on.

mod common;

use common::*;
use plumbline_slam::graph::{
    Edge, EdgeId, LoopKernel, NodeId, OptimizeConfig, OptimizeReport, Pose2d, PoseGraph,
};

struct Run {
    graph: PoseGraph,
    reports: Vec<OptimizeReport>,
    /// Edge ids of the false loops.
    false_ids: Vec<EdgeId>,
}

/// Builds the graph as a front end does: each node placed by its odometry from the current
/// estimate of the previous node, each loop added when its later node arrives, and the graph
/// optimised after every loop.
fn incremental(
    seed: u64,
    nodes: usize,
    false_loops: usize,
    config: &OptimizeConfig,
) -> (Run, Vec<Pose2d>) {
    let mut rng = Rng::new(seed);
    let truth = manhattan_truth(&mut rng, nodes, 8);
    let pairs = loop_pairs(&truth, 40);
    // False loops: late nodes claimed to be at a node several metres from where they are,
    // drawn from their own stream so the odometry and loop noise match the run without them.
    let mut wrong_rng = Rng::new(seed ^ 0xFA15E);
    let mut wrong: Vec<(usize, Edge)> = Vec::new();
    while wrong.len() < false_loops {
        let j = nodes / 3 + wrong_rng.index(2 * nodes / 3);
        let (i, k) = (wrong_rng.index(j / 2), wrong_rng.index(j));
        let off = (truth[k].x - truth[j].x).hypot(truth[k].y - truth[j].y);
        if off > 3.0 {
            wrong.push((j, false_loop_edge(&truth, i, j, k)));
        }
    }
    let mut graph = PoseGraph::new();
    graph.add_node(truth[0]).unwrap();
    let (mut reports, mut false_ids) = (Vec::new(), Vec::new());
    for j in 1..nodes {
        let odom = odometry_edge(&mut rng, &truth, j - 1);
        let guess = graph
            .pose(NodeId(j as u32 - 1))
            .unwrap()
            .compose(odom.measurement);
        graph.add_node(guess).unwrap();
        graph.add_edge(odom).unwrap();
        let mut loops: Vec<Edge> = pairs
            .iter()
            .filter(|p| p.1 == j)
            .map(|&(i, j)| loop_edge(&mut rng, &truth, i, j))
            .collect();
        let first_false = loops.len();
        loops.extend(wrong.iter().filter(|w| w.0 == j).map(|w| w.1));
        for (n, edge) in loops.into_iter().enumerate() {
            let id = graph.add_edge(edge).unwrap();
            if n >= first_false {
                false_ids.push(id);
            }
            reports.push(graph.optimize(config));
        }
    }
    (
        Run {
            graph,
            reports,
            false_ids,
        },
        truth,
    )
}

const SEEDS: [u64; 3] = [1, 2, 3];

#[test]
fn loops_pull_the_drifting_odometry_back_to_the_truth() {
    for seed in SEEDS {
        let mut rng = Rng::new(seed);
        let truth = manhattan_truth(&mut rng, 600, 8);
        let odometry = odometry_graph(&mut rng, &truth);
        let odometry_error = rms_error_m(&odometry, &truth);
        let (run, truth2) = incremental(seed, 600, 0, &OptimizeConfig::default());
        assert_eq!(truth, truth2);
        let error = rms_error_m(&run.graph, &truth);
        let last = run.reports.last().unwrap();
        println!(
            "seed {seed}: odometry {odometry_error:.3} m, optimised {error:.3} m, {} optimisations, last {} iterations {:.1} -> {:.1} in {:?}",
            run.reports.len(), last.iterations, last.initial_chi2, last.final_chi2, last.elapsed
        );
        assert!(run
            .reports
            .iter()
            .all(|r| r.converged && r.final_chi2.is_finite()));
        assert!(run.reports.iter().all(|r| r.downweighted_loops.is_empty()));
        assert!(
            error < odometry_error / 5.0,
            "seed {seed}: {error} vs {odometry_error}"
        );
    }
}

#[test]
fn false_loops_are_rejected_by_the_kernel_and_bend_the_map_without_it() {
    for seed in SEEDS {
        let robust = OptimizeConfig::default();
        let (clean, truth) = incremental(seed, 600, 0, &robust);
        let (noisy, _) = incremental(seed, 600, 4, &robust);
        let plain = OptimizeConfig {
            loop_kernel: LoopKernel::None,
            ..robust
        };
        let (bent, _) = incremental(seed, 600, 4, &plain);
        let clean_error = rms_error_m(&clean.graph, &truth);
        let robust_error = rms_error_m(&noisy.graph, &truth);
        let plain_error = rms_error_m(&bent.graph, &truth);
        let last = noisy.reports.last().unwrap();
        println!(
            "seed {seed}: clean {clean_error:.3} m, 4 false loops with DCS {robust_error:.3} m, without kernel {plain_error:.3} m; down-weighted {:?}, false {:?}",
            last.downweighted_loops, noisy.false_ids
        );
        assert_eq!(last.downweighted_loops, noisy.false_ids, "seed {seed}");
        for id in &noisy.false_ids {
            assert!(last.edge_weights[id.index()] < 0.01);
        }
        assert!((robust_error - clean_error).abs() < 0.01, "seed {seed}");
        assert!(
            plain_error > 5.0 * robust_error && plain_error > 0.3,
            "seed {seed}"
        );
    }
}
