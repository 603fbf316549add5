//! Pose-graph optimisation on a synthetic 2,000-node Manhattan walk: a cold batch solve from
//! odometry, the warm call after one more loop closure (what the front end does after each
//! accepted loop), and a solve on a graph already at its optimum.
//!
//! `cargo bench -p plumbline-slam --bench graph`

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use plumbline_slam::graph::{OptimizeConfig, PoseGraph};
use std::hint::black_box;

/// The walk with every loop but the last added and optimised, and that last loop.
fn before_last_loop(loops: usize) -> (PoseGraph, plumbline_slam::graph::Edge, PoseGraph) {
    let (mut graph, _, edges) = common::bench_graph(7, 2000, loops);
    let mut cold = graph.clone();
    for e in &edges {
        cold.add_edge(*e).unwrap();
    }
    let (last, rest) = edges.split_last().unwrap();
    for e in rest {
        graph.add_edge(*e).unwrap();
    }
    let report = graph.optimize(&OptimizeConfig::default());
    assert!(report.converged);
    (graph, *last, cold)
}

fn bench(c: &mut Criterion) {
    let config = OptimizeConfig::default();
    for loops in [50, 1000] {
        let (warm, last, cold) = before_last_loop(loops);
        let edges = cold.edges().len();
        c.bench_function(&format!("graph_batch_from_odometry_2000n_{edges}e"), |b| {
            b.iter_batched(
                || cold.clone(),
                |mut g| black_box(g.optimize(&config)),
                BatchSize::LargeInput,
            )
        });
        c.bench_function(&format!("graph_after_one_more_loop_2000n_{edges}e"), |b| {
            b.iter_batched(
                || {
                    let mut g = warm.clone();
                    g.add_edge(last).unwrap();
                    g
                },
                |mut g| black_box(g.optimize(&config)),
                BatchSize::LargeInput,
            )
        });
        let mut done = warm.clone();
        done.add_edge(last).unwrap();
        done.optimize(&config);
        // Touching a pose makes the graph solve again (an unchanged graph returns at once):
        // the cost of one linearise-factor-solve at the optimum.
        let last_node = plumbline_slam::graph::NodeId(done.nodes().len() as u32 - 1);
        let at = done.pose(last_node).unwrap();
        c.bench_function(&format!("graph_resolve_at_optimum_2000n_{edges}e"), |b| {
            b.iter(|| {
                done.set_pose(last_node, at).unwrap();
                black_box(done.optimize(&config))
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
