//! A small local map that keyframes are aligned with, to cut the drift of scan-to-keyframe
//! odometry: each keyframe's heading is tied to walls mapped long before.

mod cells;
mod mapped;
mod refine;
mod relocalize;

/// The prior's information matrix type of [`refine`].
pub use crate::matching::linalg::Sym3;
pub use cells::{CellLine, LineMap, LineMapConfig, LineMapError, MapCell};
pub use mapped::{MapUse, MappedOdometry, MappedStep};
pub use refine::{correction_is_plausible, map_age, refine, RefineConfig, RefineRefusal, Refined};
pub use relocalize::{relocalize, Declined, RelocalizeConfig, SearchScores};
