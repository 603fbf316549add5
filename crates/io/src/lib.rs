//! Files and devices around `plumbline-core`: CARMEN logs, relations, trajectories, sensor
//! logs as CSV and the relations metric; the one way every command opens its inputs and writes
//! its outputs.
#![forbid(unsafe_code)]

pub mod carmen;
pub mod eval;
pub mod input;
pub mod link_port;
pub mod output;
mod pose_math;
pub mod relations;
pub mod sensor_csv;
pub mod serial;
mod text_table;
pub mod trajectory;
