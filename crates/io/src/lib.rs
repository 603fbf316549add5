//! Files and devices around `plumbline-core`: CARMEN logs, relations, trajectories.
#![forbid(unsafe_code)]

pub mod carmen;
