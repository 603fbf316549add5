//! Files and devices around `plumbline-core`: CARMEN logs, relations, trajectories and the
//! relations metric.
#![forbid(unsafe_code)]

pub mod carmen;
pub mod eval;
mod pose_math;
pub mod relations;
pub mod serial;
mod text_table;
pub mod trajectory;
