//! Graph elements (ids, edges, information matrices) and the checks an edge must pass before
//! it may enter the graph: a NaN or an indefinite information matrix would not fail loudly in
//! the solver, it would quietly wreck the whole map, so they are refused at the door.

use super::pose::Pose2d;
use std::fmt;

/// Index of a node, in the order nodes were added (the first is 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

impl NodeId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Index of an edge, in the order edges were added; report weights are indexed by it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EdgeId(pub u32);

impl EdgeId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Inverse covariance of a measurement, rows and columns in the order x, y, theta.
pub type Information = [[f64; 3]; 3];

/// Diagonal information for independent errors with standard deviations `sigma_xy_m` (both
/// axes) and `sigma_theta_rad`.
pub fn diagonal_information(sigma_xy_m: f64, sigma_theta_rad: f64) -> Information {
    let (a, t) = (
        1.0 / (sigma_xy_m * sigma_xy_m),
        1.0 / (sigma_theta_rad * sigma_theta_rad),
    );
    [[a, 0.0, 0.0], [0.0, a, 0.0], [0.0, 0.0, t]]
}

/// Where an edge came from. Only loop edges get the robust kernel: odometry between
/// consecutive keyframes is what holds the map together while a false loop is being rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeKind {
    Odometry,
    Loop,
}

/// A relative-pose constraint: `measurement` is the pose of `to` in the frame of `from`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    pub from: NodeId,
    pub to: NodeId,
    pub measurement: Pose2d,
    pub information: Information,
    pub kind: EdgeKind,
}

/// Why the graph refused a node, an edge or a request.
#[derive(Clone, Debug, PartialEq)]
pub enum GraphError {
    /// The node id is not in the graph (it has `nodes` nodes).
    UnknownNode { node: NodeId, nodes: usize },
    /// An edge from a node to itself constrains nothing and would only add noise.
    SelfLoop { node: NodeId },
    /// A pose or measurement with a NaN or infinite component.
    NonFinitePose { what: &'static str },
    /// An information entry that is NaN or infinite.
    NonFiniteInformation { row: usize, col: usize },
    /// The information matrix differs from its transpose at (row, col).
    InformationNotSymmetric { row: usize, col: usize },
    /// The information matrix has a non-positive pivot: some direction carries no (or negative)
    /// confidence, which the normal equations cannot hold.
    InformationNotPositiveDefinite,
    /// The graph already holds `u32::MAX` nodes or edges.
    TooLarge,
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GraphError::UnknownNode { node, nodes } => write!(
                f,
                "node {} does not exist (the graph has {nodes} nodes); add the node before its edges",
                node.0
            ),
            GraphError::SelfLoop { node } => {
                write!(f, "edge from node {} to itself; an edge must join two different nodes", node.0)
            }
            GraphError::NonFinitePose { what } => {
                write!(f, "{what} has a NaN or infinite component; pass finite x, y, theta")
            }
            GraphError::NonFiniteInformation { row, col } => {
                write!(f, "information entry ({row}, {col}) is NaN or infinite")
            }
            GraphError::InformationNotSymmetric { row, col } => write!(
                f,
                "information matrix is not symmetric at ({row}, {col}); pass the inverse covariance"
            ),
            GraphError::InformationNotPositiveDefinite => write!(
                f,
                "information matrix is not positive definite; every direction (x, y, theta) needs a positive confidence"
            ),
            GraphError::TooLarge => write!(f, "the graph is full (u32::MAX nodes or edges)"),
        }
    }
}

impl std::error::Error for GraphError {}

/// Checks that `info` is finite, symmetric (to a relative 1e-9) and positive definite.
pub fn check_information(info: &Information) -> Result<(), GraphError> {
    for (row, values) in info.iter().enumerate() {
        for (col, v) in values.iter().enumerate() {
            if !v.is_finite() {
                return Err(GraphError::NonFiniteInformation { row, col });
            }
        }
    }
    for (row, col) in [(0, 1), (0, 2), (1, 2)] {
        let (a, b) = (info[row][col], info[col][row]);
        if (a - b).abs() > 1e-9 * a.abs().max(b.abs()).max(f64::MIN_POSITIVE) {
            return Err(GraphError::InformationNotSymmetric { row, col });
        }
    }
    // LDL^T pivots, all positive for a positive-definite matrix; this form divides before it
    // multiplies, so a huge but valid information (1e150) does not overflow as minors would.
    let m = info;
    let d0 = m[0][0];
    let (l10, l20) = (m[1][0] / d0, m[2][0] / d0);
    let d1 = m[1][1] - l10 * m[1][0];
    let l21 = (m[2][1] - l20 * m[1][0]) / d1;
    let d2 = m[2][2] - l20 * m[2][0] - l21 * (m[2][1] - l20 * m[1][0]);
    if [d0, d1, d2].iter().all(|d| *d > 0.0 && d.is_finite()) {
        Ok(())
    } else {
        Err(GraphError::InformationNotPositiveDefinite)
    }
}

/// An odometry edge with unit-ish information, for the module tests.
#[cfg(test)]
pub(super) fn test_edge(from: u32, to: u32, measurement: Pose2d) -> Edge {
    Edge {
        from: NodeId(from),
        to: NodeId(to),
        measurement,
        information: diagonal_information(0.1, 0.01),
        kind: EdgeKind::Odometry,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn information_checks_name_the_fault() {
        let good = diagonal_information(0.1, 0.01);
        assert_eq!(check_information(&good), Ok(()));
        let mut nan = good;
        nan[2][1] = f64::NAN;
        assert_eq!(
            check_information(&nan),
            Err(GraphError::NonFiniteInformation { row: 2, col: 1 })
        );
        let mut skew = good;
        skew[0][2] = 1.0;
        assert_eq!(
            check_information(&skew),
            Err(GraphError::InformationNotSymmetric { row: 0, col: 2 })
        );
        let mut indefinite = good;
        indefinite[0][1] = 200.0;
        indefinite[1][0] = 200.0;
        assert_eq!(
            check_information(&indefinite),
            Err(GraphError::InformationNotPositiveDefinite)
        );
        let zero_theta = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
        assert_eq!(
            check_information(&zero_theta),
            Err(GraphError::InformationNotPositiveDefinite)
        );
        let huge = [[1e150, 1e149, 0.0], [1e149, 1e150, 0.0], [0.0, 0.0, 1e150]];
        assert_eq!(check_information(&huge), Ok(()));
    }
}
