//! The pose graph: keyframe poses joined by odometry and loop-closure constraints, optimised
//! by sparse Levenberg-Marquardt with a robust kernel on loops, and read and written as g2o
//! text so other tools (g2o_viewer, the Freiburg datasets) can exchange graphs with it.

mod edge;
mod g2o;
mod graduation;
mod kernel;
mod optimize;
mod pattern;
mod pose;
mod pose_graph;
mod residual;
mod solver;

pub use edge::{diagonal_information, Edge, EdgeId, EdgeKind, GraphError, Information, NodeId};
pub use g2o::{read_g2o, write_g2o, G2oError, G2oErrorKind};
pub use kernel::LoopKernel;
pub use optimize::{OptimizeConfig, OptimizeReport, StopReason};
pub use pose::Pose2d;
pub use pose_graph::PoseGraph;
