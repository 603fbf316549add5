//! g2o text I/O for 2-D pose graphs, the format of g2o, g2o_viewer and the public benchmark
//! graphs (intel.g2o, M3500): one element per line,
//! `VERTEX_SE2 id x y theta`,
//! `EDGE_SE2 from to dx dy dtheta i11 i12 i13 i22 i23 i33` (the upper triangle of the
//! information, row by row) and `FIX id...`. Lines starting with `#` and blank lines are skipped.
//!
//! g2o has no notion of edge kind, so the reader calls an edge odometry when it joins vertices
//! declared one after the other (`|from - to| = 1` in declaration order) and a loop otherwise,
//! the convention of the robust-SLAM benchmark graphs. Vertex ids may be any integers; they
//! become node ids in declaration order, and the writer writes node ids, so write-then-read
//! returns the same graph. Numbers are written in Rust's shortest round-trip form.

use super::edge::{Edge, EdgeKind, GraphError, NodeId};
use super::pose::Pose2d;
use super::pose_graph::PoseGraph;
use std::collections::HashMap;
use std::fmt;
use std::io::{self, BufRead, Write};

/// Writes every node, every edge and a `FIX` line per fixed node.
pub fn write_g2o(graph: &PoseGraph, mut out: impl Write) -> io::Result<()> {
    for (id, p) in graph.nodes().iter().enumerate() {
        writeln!(out, "VERTEX_SE2 {id} {} {} {}", p.x, p.y, p.theta)?;
    }
    for e in graph.edges() {
        let (m, i) = (e.measurement, e.information);
        writeln!(
            out,
            "EDGE_SE2 {} {} {} {} {} {} {} {} {} {} {}",
            e.from.0,
            e.to.0,
            m.x,
            m.y,
            m.theta,
            i[0][0],
            i[0][1],
            i[0][2],
            i[1][1],
            i[1][2],
            i[2][2]
        )?;
    }
    for id in 0..graph.nodes().len() {
        if graph.is_fixed(NodeId(id as u32)) {
            writeln!(out, "FIX {id}")?;
        }
    }
    Ok(())
}

/// A g2o line that could not be read: its 1-based number and what was wrong with it.
#[derive(Clone, Debug, PartialEq)]
pub struct G2oError {
    pub line: usize,
    pub kind: G2oErrorKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum G2oErrorKind {
    /// Reading failed (or the bytes are not UTF-8).
    Io(String),
    /// A tag other than VERTEX_SE2, EDGE_SE2 or FIX.
    UnsupportedTag(String),
    MissingField {
        tag: &'static str,
        field: &'static str,
    },
    ExtraField {
        tag: &'static str,
        text: String,
    },
    BadNumber {
        tag: &'static str,
        field: &'static str,
        text: String,
    },
    DuplicateVertex(i64),
    /// An edge or FIX naming a vertex not declared on an earlier line.
    UnknownVertex {
        field: &'static str,
        id: i64,
    },
    /// The graph refused the vertex or edge (non-finite value, non-PD information, self-loop).
    Rejected(GraphError),
}

impl fmt::Display for G2oError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: ", self.line)?;
        match &self.kind {
            G2oErrorKind::Io(e) => write!(f, "could not read: {e}"),
            G2oErrorKind::UnsupportedTag(t) => write!(
                f,
                "unsupported element '{t}'; only VERTEX_SE2, EDGE_SE2 and FIX (2-D pose graphs) are read"
            ),
            G2oErrorKind::MissingField { tag, field } => write!(f, "{tag} ends before field '{field}'"),
            G2oErrorKind::ExtraField { tag, text } => write!(f, "{tag} has an extra field '{text}'"),
            G2oErrorKind::BadNumber { tag, field, text } => {
                write!(f, "{tag} field '{field}' is not a number: '{text}'")
            }
            G2oErrorKind::DuplicateVertex(id) => write!(f, "vertex {id} is declared twice"),
            G2oErrorKind::UnknownVertex { field, id } => write!(
                f,
                "field '{field}' names vertex {id}, which no earlier VERTEX_SE2 line declares"
            ),
            G2oErrorKind::Rejected(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for G2oError {}

const VERTEX: &str = "VERTEX_SE2";
const VERTEX_FIELDS: [&str; 4] = ["id", "x", "y", "theta"];
const EDGE: &str = "EDGE_SE2";
const EDGE_FIELDS: [&str; 11] = [
    "from", "to", "dx", "dy", "dtheta", "i11", "i12", "i13", "i22", "i23", "i33",
];

/// Reads a 2-D pose graph; the first error stops the read and names its line and field.
pub fn read_g2o(input: impl BufRead) -> Result<PoseGraph, G2oError> {
    let mut graph = PoseGraph::new();
    let mut ids: HashMap<i64, NodeId> = HashMap::new();
    for (index, line) in input.lines().enumerate() {
        let line_no = index + 1;
        let fail = |kind| G2oError {
            line: line_no,
            kind,
        };
        let line = line.map_err(|e| fail(G2oErrorKind::Io(e.to_string())))?;
        let mut tokens = line.split_whitespace();
        let Some(tag) = tokens.next() else { continue };
        if tag.starts_with('#') {
            continue;
        }
        let lookup = |field: &'static str, id: i64| {
            ids.get(&id)
                .copied()
                .ok_or(G2oErrorKind::UnknownVertex { field, id })
        };
        let result = match tag {
            VERTEX => numbers(VERTEX, &VERTEX_FIELDS, &mut tokens).and_then(|v: [f64; 4]| {
                let id = integer(VERTEX, "id", v[0])?;
                if ids.contains_key(&id) {
                    return Err(G2oErrorKind::DuplicateVertex(id));
                }
                let node = graph
                    .add_node(Pose2d::new(v[1], v[2], v[3]))
                    .map_err(G2oErrorKind::Rejected)?;
                ids.insert(id, node);
                Ok(())
            }),
            EDGE => numbers(EDGE, &EDGE_FIELDS, &mut tokens).and_then(|v: [f64; 11]| {
                let from = lookup("from", integer(EDGE, "from", v[0])?)?;
                let to = lookup("to", integer(EDGE, "to", v[1])?)?;
                let kind = if from.0.abs_diff(to.0) == 1 {
                    EdgeKind::Odometry
                } else {
                    EdgeKind::Loop
                };
                let edge = Edge {
                    from,
                    to,
                    measurement: Pose2d::new(v[2], v[3], v[4]),
                    information: [[v[5], v[6], v[7]], [v[6], v[8], v[9]], [v[7], v[9], v[10]]],
                    kind,
                };
                graph
                    .add_edge(edge)
                    .map(|_| ())
                    .map_err(G2oErrorKind::Rejected)
            }),
            "FIX" => tokens.try_for_each(|text| {
                let id = text.parse::<i64>().map_err(|_| G2oErrorKind::BadNumber {
                    tag: "FIX",
                    field: "id",
                    text: text.to_string(),
                })?;
                graph.fix(lookup("id", id)?).map_err(G2oErrorKind::Rejected)
            }),
            other => Err(G2oErrorKind::UnsupportedTag(other.to_string())),
        };
        result.map_err(fail)?;
    }
    Ok(graph)
}

/// Parses exactly `N` numeric fields and refuses anything after them.
fn numbers<'a, const N: usize>(
    tag: &'static str,
    fields: &[&'static str; N],
    tokens: &mut impl Iterator<Item = &'a str>,
) -> Result<[f64; N], G2oErrorKind> {
    let mut out = [0.0; N];
    for (value, field) in out.iter_mut().zip(fields) {
        let text = tokens
            .next()
            .ok_or(G2oErrorKind::MissingField { tag, field })?;
        *value = text.parse().map_err(|_| G2oErrorKind::BadNumber {
            tag,
            field,
            text: text.to_string(),
        })?;
    }
    match tokens.next() {
        Some(text) => Err(G2oErrorKind::ExtraField {
            tag,
            text: text.to_string(),
        }),
        None => Ok(out),
    }
}

/// A vertex id: a whole number small enough to be exact in f64.
fn integer(tag: &'static str, field: &'static str, v: f64) -> Result<i64, G2oErrorKind> {
    if v.fract() == 0.0 && v.abs() < 9.0e15 {
        Ok(v as i64)
    } else {
        Err(G2oErrorKind::BadNumber {
            tag,
            field,
            text: v.to_string(),
        })
    }
}
