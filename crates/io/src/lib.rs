//! Files and devices around `plumbline-core`: CARMEN logs, relations, trajectories, sensor
//! logs as CSV, the relations metric, and the one way output files are created.
#![forbid(unsafe_code)]

pub mod carmen;
pub mod eval;
pub mod output;
mod pose_math;
pub mod relations;
pub mod sensor_csv;
pub mod serial;
mod text_table;
pub mod trajectory;
