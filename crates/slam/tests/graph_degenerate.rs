//! Inputs that could break a solver: no edges, enormous information, pieces of graph with
//! no fixed node, contradictory edges. Each must end with finite poses and a report, never a
//! panic or a NaN.

use plumbline_slam::graph::{
    diagonal_information, Edge, EdgeKind, NodeId, OptimizeConfig, Pose2d, PoseGraph, StopReason,
};

fn edge(from: u32, to: u32, m: Pose2d, sigma: f64, kind: EdgeKind) -> Edge {
    Edge {
        from: NodeId(from),
        to: NodeId(to),
        measurement: m,
        information: diagonal_information(sigma, sigma),
        kind,
    }
}

fn all_finite(g: &PoseGraph) -> bool {
    g.nodes().iter().all(|p| p.is_finite())
}

#[test]
fn empty_graph_and_graph_without_edges_are_left_alone() {
    let mut g = PoseGraph::new();
    let r = g.optimize(&OptimizeConfig::default());
    assert_eq!(
        (r.stop, r.iterations, r.final_chi2),
        (StopReason::NothingToOptimize, 0, 0.0)
    );
    for k in 0..5 {
        g.add_node(Pose2d::new(k as f64, 0.5, 0.1)).unwrap();
    }
    let before = g.nodes().to_vec();
    let r = g.optimize(&OptimizeConfig::default());
    assert!(r.converged && r.final_chi2 == 0.0);
    assert_eq!(r.anchored, [NodeId(1), NodeId(2), NodeId(3), NodeId(4)]);
    assert_eq!(g.nodes(), before.as_slice());
}

#[test]
fn huge_information_is_honoured_without_nan() {
    let mut g = PoseGraph::new();
    for k in 0..4 {
        // Node 0 (fixed) at the origin, the others off the line the edges ask for.
        let k = k as f64;
        g.add_node(Pose2d::new(k * 1.1, 0.2 * k, 0.05 * k)).unwrap();
    }
    let step = Pose2d::new(1.0, 0.0, 0.0);
    g.add_edge(edge(0, 1, step, 1e-7, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(1, 2, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(2, 3, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(0, 3, Pose2d::new(3.0, 0.0, 0.0), 1e-6, EdgeKind::Loop))
        .unwrap();
    let r = g.optimize(&OptimizeConfig::default());
    assert!(
        r.converged && r.final_chi2.is_finite() && all_finite(&g),
        "{r:?}"
    );
    let p1 = g.pose(NodeId(1)).unwrap();
    let p3 = g.pose(NodeId(3)).unwrap();
    assert!((p1.x - 1.0).abs() < 1e-6 && p1.y.abs() < 1e-6, "{p1:?}");
    assert!((p3.x - 3.0).abs() < 1e-5 && p3.y.abs() < 1e-5, "{p3:?}");
}

#[test]
fn a_component_without_fixed_node_is_anchored_at_its_first_node() {
    let mut g = PoseGraph::new();
    for k in 0..6 {
        g.add_node(Pose2d::new(k as f64, 1.0, 0.0)).unwrap();
    }
    let step = Pose2d::new(2.0, 0.0, 0.0);
    g.add_edge(edge(0, 1, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(1, 2, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(3, 4, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(4, 5, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    let anchor = g.pose(NodeId(3)).unwrap();
    let r = g.optimize(&OptimizeConfig::default());
    assert!(r.converged && all_finite(&g));
    assert_eq!(r.anchored, [NodeId(3)]);
    assert_eq!(g.pose(NodeId(3)).unwrap(), anchor);
    assert!((g.pose(NodeId(5)).unwrap().x - (anchor.x + 4.0)).abs() < 1e-6);
    assert!((g.pose(NodeId(2)).unwrap().x - 4.0).abs() < 1e-6);
}

#[test]
fn contradictory_edges_end_finite_with_the_odometry_kept() {
    let mut g = PoseGraph::new();
    for k in 0..3 {
        g.add_node(Pose2d::new(k as f64, 0.0, 0.0)).unwrap();
    }
    let step = Pose2d::new(1.0, 0.0, 0.0);
    g.add_edge(edge(0, 1, step, 0.01, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(1, 2, step, 0.01, EdgeKind::Odometry))
        .unwrap();
    // Two loops between the same nodes claiming opposite places and headings.
    g.add_edge(edge(
        0,
        2,
        Pose2d::new(-50.0, 3.0, 3.0),
        0.01,
        EdgeKind::Loop,
    ))
    .unwrap();
    g.add_edge(edge(
        2,
        0,
        Pose2d::new(50.0, -3.0, -3.0),
        0.01,
        EdgeKind::Loop,
    ))
    .unwrap();
    let r = g.optimize(&OptimizeConfig::default());
    assert!(r.final_chi2.is_finite() && all_finite(&g), "{r:?}");
    assert_eq!(r.downweighted_loops.len(), 2);
    assert!((g.pose(NodeId(2)).unwrap().x - 2.0).abs() < 1e-3);
}

#[test]
fn an_unchanged_graph_is_not_solved_again_but_any_change_is() {
    let mut g = PoseGraph::new();
    for k in 0..3 {
        g.add_node(Pose2d::new(k as f64 * 1.2, 0.3 * k as f64, 0.0))
            .unwrap();
    }
    let step = Pose2d::new(1.0, 0.0, 0.0);
    g.add_edge(edge(0, 1, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    g.add_edge(edge(1, 2, step, 0.1, EdgeKind::Odometry))
        .unwrap();
    let config = OptimizeConfig::default();
    assert!(g.optimize(&config).iterations > 0);
    let again = g.optimize(&config);
    assert!(again.converged && again.iterations == 0);
    g.set_pose(NodeId(2), Pose2d::new(5.0, 1.0, 0.0)).unwrap();
    assert!(g.optimize(&config).iterations > 0);
    assert!((g.pose(NodeId(2)).unwrap().x - 2.0).abs() < 1e-6);
}
