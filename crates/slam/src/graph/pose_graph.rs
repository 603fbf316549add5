//! The pose graph: poses as nodes, relative-pose measurements as edges.

use super::edge::{check_information, Edge, EdgeId, GraphError, NodeId};
use super::pattern::Pattern;
use super::pose::Pose2d;

/// Nodes (f64 poses), edges, and which nodes stay where they are when the graph is optimised.
///
/// The first node added is fixed: a pose graph only knows poses relative to each other, so
/// one pose must be held to pin the whole map in the world. Components that are not joined to
/// a fixed node by any chain of edges are pinned at their lowest node while optimising (see
/// [`PoseGraph::optimize`](super::optimize)), so a gap in the front end's chain never leaves a
/// floating piece for the solver to trip on.
#[derive(Clone, Debug, Default)]
pub struct PoseGraph {
    poses: Vec<Pose2d>,
    fixed: Vec<bool>,
    edges: Vec<Edge>,
    /// The normal equations' sparsity pattern and its symbolic factorisation, kept while no
    /// node, edge or fixed flag has been added, so repeated optimisations skip that work.
    pub(super) pattern: Option<Pattern>,
    /// Loop edges the last optimisation down-weighted, indexed like `edges`; they skip the
    /// graduated start of the next one (see `super::graduation`).
    rejected: Vec<bool>,
    /// The settings of the last optimisation if it converged and no edge, pose or fixed flag
    /// has changed since: optimising again with them would find the same poses.
    pub(super) settled: Option<super::optimize::OptimizeConfig>,
}

impl PoseGraph {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a pose (heading wrapped to (-pi, pi]); refuses a non-finite one.
    pub fn add_node(&mut self, pose: Pose2d) -> Result<NodeId, GraphError> {
        if !pose.is_finite() {
            return Err(GraphError::NonFinitePose { what: "node pose" });
        }
        let id = u32::try_from(self.poses.len()).map_err(|_| GraphError::TooLarge)?;
        self.fixed.push(self.poses.is_empty());
        self.poses.push(Pose2d::new(pose.x, pose.y, pose.theta));
        self.pattern = None;
        Ok(NodeId(id))
    }

    /// Adds a constraint after checking its nodes, measurement and information.
    pub fn add_edge(&mut self, edge: Edge) -> Result<EdgeId, GraphError> {
        self.check_node(edge.from)?;
        self.check_node(edge.to)?;
        if edge.from == edge.to {
            return Err(GraphError::SelfLoop { node: edge.from });
        }
        if !edge.measurement.is_finite() {
            return Err(GraphError::NonFinitePose {
                what: "edge measurement",
            });
        }
        check_information(&edge.information)?;
        let id = u32::try_from(self.edges.len()).map_err(|_| GraphError::TooLarge)?;
        let m = edge.measurement;
        self.rejected.push(false);
        self.edges.push(Edge {
            measurement: Pose2d::new(m.x, m.y, m.theta),
            ..edge
        });
        self.pattern = None;
        self.settled = None;
        Ok(EdgeId(id))
    }

    pub fn pose(&self, id: NodeId) -> Option<Pose2d> {
        self.poses.get(id.index()).copied()
    }

    /// Moves a node (the front end's new guess, or a reset); refuses a non-finite pose.
    pub fn set_pose(&mut self, id: NodeId, pose: Pose2d) -> Result<(), GraphError> {
        self.check_node(id)?;
        if !pose.is_finite() {
            return Err(GraphError::NonFinitePose { what: "node pose" });
        }
        self.poses[id.index()] = Pose2d::new(pose.x, pose.y, pose.theta);
        self.settled = None;
        Ok(())
    }

    /// Holds a node where it is during optimisation.
    pub fn fix(&mut self, id: NodeId) -> Result<(), GraphError> {
        self.check_node(id)?;
        if !self.fixed[id.index()] {
            self.fixed[id.index()] = true;
            self.pattern = None;
            self.settled = None;
        }
        Ok(())
    }

    pub fn is_fixed(&self, id: NodeId) -> bool {
        self.fixed.get(id.index()).copied().unwrap_or(false)
    }

    /// All poses, indexed by `NodeId::index`.
    pub fn nodes(&self) -> &[Pose2d] {
        &self.poses
    }

    /// All edges, indexed by `EdgeId::index`.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    pub(super) fn fixed_flags(&self) -> &[bool] {
        &self.fixed
    }

    pub(super) fn was_rejected(&self, edge: usize) -> bool {
        self.rejected.get(edge).copied().unwrap_or(false)
    }

    pub(super) fn remember_rejected(&mut self, rejected: &[EdgeId]) {
        self.rejected.fill(false);
        for id in rejected {
            self.rejected[id.index()] = true;
        }
    }

    pub(super) fn poses_mut(&mut self) -> &mut [Pose2d] {
        &mut self.poses
    }

    fn check_node(&self, node: NodeId) -> Result<(), GraphError> {
        if node.index() < self.poses.len() {
            Ok(())
        } else {
            Err(GraphError::UnknownNode {
                node,
                nodes: self.poses.len(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::edge::test_edge;
    use super::*;

    fn edge(from: u32, to: u32) -> Edge {
        test_edge(from, to, Pose2d::new(1.0, 0.0, 0.0))
    }

    #[test]
    fn bad_edges_and_nodes_are_refused_with_the_reason() {
        let mut g = PoseGraph::new();
        let a = g.add_node(Pose2d::IDENTITY).unwrap();
        let b = g.add_node(Pose2d::new(1.0, 0.0, 7.0)).unwrap();
        assert!(g.is_fixed(a) && !g.is_fixed(b));
        assert!(g.pose(b).unwrap().theta <= std::f64::consts::PI);
        assert_eq!(
            g.add_node(Pose2d::new(f64::NAN, 0.0, 0.0)),
            Err(GraphError::NonFinitePose { what: "node pose" })
        );
        assert_eq!(
            g.add_edge(edge(0, 5)),
            Err(GraphError::UnknownNode {
                node: NodeId(5),
                nodes: 2
            })
        );
        assert_eq!(
            g.add_edge(edge(1, 1)),
            Err(GraphError::SelfLoop { node: NodeId(1) })
        );
        let mut inf = edge(0, 1);
        inf.measurement.y = f64::INFINITY;
        assert!(matches!(
            g.add_edge(inf),
            Err(GraphError::NonFinitePose { .. })
        ));
        assert_eq!(g.add_edge(edge(0, 1)), Ok(EdgeId(0)));
        assert_eq!(g.edges().len(), 1);
        assert!(g.set_pose(NodeId(9), Pose2d::IDENTITY).is_err());
        assert!(g
            .set_pose(b, Pose2d::new(0.0, f64::NEG_INFINITY, 0.0))
            .is_err());
    }
}
