//! g2o text: write-then-read returns the same graph, and every malformed line is refused with
//! its line number and field.

use plumbline_slam::graph::{
    read_g2o, write_g2o, Edge, EdgeKind, G2oErrorKind, GraphError, NodeId, Pose2d, PoseGraph,
};
use proptest::prelude::*;

fn pose() -> impl Strategy<Value = Pose2d> {
    (-1e3..1e3f64, -1e3..1e3f64, -3.2..3.2f64).prop_map(|(x, y, t)| Pose2d::new(x, y, t))
}

/// A positive-definite information `L L^T + eps I` from arbitrary lower-triangular entries.
fn information() -> impl Strategy<Value = [[f64; 3]; 3]> {
    prop::array::uniform6(-30.0..30.0f64).prop_map(|l| {
        let low = [[l[0], 0.0, 0.0], [l[1], l[2], 0.0], [l[3], l[4], l[5]]];
        let mut m = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = (0..3).map(|k| low[r][k] * low[c][k]).sum::<f64>();
            }
            m[r][r] += 0.1;
        }
        m
    })
}

fn graph() -> impl Strategy<Value = PoseGraph> {
    let nodes = prop::collection::vec(pose(), 2..30);
    nodes
        .prop_flat_map(|poses| {
            let n = poses.len() as u32;
            let edge = (0..n, 0..n, pose(), information());
            (
                Just(poses),
                prop::collection::vec(edge, 0..40),
                prop::collection::vec(0..n, 0..3),
            )
        })
        .prop_map(|(poses, edges, fixed)| {
            let mut g = PoseGraph::new();
            for p in poses {
                g.add_node(p).unwrap();
            }
            for (from, to, measurement, information) in edges {
                // The reader's convention: consecutive nodes are odometry, others loops.
                let kind = if from.abs_diff(to) == 1 {
                    EdgeKind::Odometry
                } else {
                    EdgeKind::Loop
                };
                let edge = Edge {
                    from: NodeId(from),
                    to: NodeId(to),
                    measurement,
                    information,
                    kind,
                };
                if from != to {
                    g.add_edge(edge).unwrap();
                }
            }
            for f in fixed {
                g.fix(NodeId(f)).unwrap();
            }
            g
        })
}

proptest! {
    #[test]
    fn write_then_read_returns_the_same_graph(g in graph()) {
        let mut text = Vec::new();
        write_g2o(&g, &mut text).unwrap();
        let back = read_g2o(text.as_slice()).unwrap();
        prop_assert_eq!(back.nodes(), g.nodes());
        prop_assert_eq!(back.edges(), g.edges());
        for k in 0..g.nodes().len() as u32 {
            prop_assert_eq!(back.is_fixed(NodeId(k)), g.is_fixed(NodeId(k)));
        }
    }
}

fn error_of(text: &str) -> (usize, G2oErrorKind) {
    let e = read_g2o(text.as_bytes()).unwrap_err();
    assert!(
        e.to_string().starts_with(&format!("line {}:", e.line)),
        "{e}"
    );
    (e.line, e.kind)
}

#[test]
fn malformed_lines_are_named() {
    let v = "VERTEX_SE2 10 0 0 0\nVERTEX_SE2 11 1 0 0\n";
    assert_eq!(
        error_of(&format!("{v}# comment\n\nEDGE_SE2 10 11 1 0 0 1 0 0 1 0\n")),
        (
            5,
            G2oErrorKind::MissingField {
                tag: "EDGE_SE2",
                field: "i33"
            }
        )
    );
    assert_eq!(
        error_of(&format!("{v}EDGE_SE2 10 11 1 0 x 1 0 0 1 0 1\n")),
        (
            3,
            G2oErrorKind::BadNumber {
                tag: "EDGE_SE2",
                field: "dtheta",
                text: "x".into()
            }
        )
    );
    assert_eq!(
        error_of(&format!("{v}EDGE_SE2 10 12 1 0 0 1 0 0 1 0 1\n")),
        (
            3,
            G2oErrorKind::UnknownVertex {
                field: "to",
                id: 12
            }
        )
    );
    assert_eq!(
        error_of(&format!("{v}EDGE_SE2 10 11 1 0 0 1 0 0 1 0 -1\n")),
        (
            3,
            G2oErrorKind::Rejected(GraphError::InformationNotPositiveDefinite)
        )
    );
    assert_eq!(
        error_of(&format!("{v}EDGE_SE2 10 11 1 0 nan 1 0 0 1 0 1\n")),
        (
            3,
            G2oErrorKind::Rejected(GraphError::NonFinitePose {
                what: "edge measurement"
            })
        )
    );
    assert_eq!(
        error_of(&format!("{v}EDGE_SE2 11 11 1 0 0 1 0 0 1 0 1\n")),
        (
            3,
            G2oErrorKind::Rejected(GraphError::SelfLoop { node: NodeId(1) })
        )
    );
    assert_eq!(
        error_of("VERTEX_SE2 1 0 0 0 7\n"),
        (
            1,
            G2oErrorKind::ExtraField {
                tag: "VERTEX_SE2",
                text: "7".into()
            }
        )
    );
    assert_eq!(
        error_of("VERTEX_SE2 1.5 0 0 0\n"),
        (
            1,
            G2oErrorKind::BadNumber {
                tag: "VERTEX_SE2",
                field: "id",
                text: "1.5".into()
            }
        )
    );
    assert_eq!(
        error_of(&format!("{v}VERTEX_SE2 10 0 0 0\n")),
        (3, G2oErrorKind::DuplicateVertex(10))
    );
    assert_eq!(
        error_of("VERTEX_XY 1 0 0\n"),
        (1, G2oErrorKind::UnsupportedTag("VERTEX_XY".into()))
    );
    assert_eq!(
        error_of(&format!("{v}FIX 3\n")),
        (3, G2oErrorKind::UnknownVertex { field: "id", id: 3 })
    );
    assert!(matches!(
        error_of("VERTEX_SE2 1 0 0 0\n\u{0}\u{ff}\n").1,
        G2oErrorKind::UnsupportedTag(_)
    ));
    assert!(matches!(
        read_g2o(&[0x56, 0xff, 0xfe, b'\n'][..]).unwrap_err().kind,
        G2oErrorKind::Io(_)
    ));
}

#[test]
fn reads_a_hand_written_graph_with_odometry_and_loop_edges() {
    let text = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 1 1 1.5707963\n\
                EDGE_SE2 0 1 1 0 0 100 0 0 100 0 1000\nEDGE_SE2 1 2 0 1 1.5707963 100 0 0 100 0 1000\n\
                EDGE_SE2 0 2 1 1 1.5707963 400 0 0 400 0 2500\nFIX 1\n";
    let g = read_g2o(text.as_bytes()).unwrap();
    assert_eq!(g.nodes().len(), 3);
    let kinds: Vec<EdgeKind> = g.edges().iter().map(|e| e.kind).collect();
    assert_eq!(
        kinds,
        [EdgeKind::Odometry, EdgeKind::Odometry, EdgeKind::Loop]
    );
    assert!(g.is_fixed(NodeId(0)) && g.is_fixed(NodeId(1)) && !g.is_fixed(NodeId(2)));
    assert_eq!(g.edges()[2].information[2][2], 2500.0);
}
