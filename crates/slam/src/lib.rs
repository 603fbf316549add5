//! Lidar-only SLAM for the companion computer (std): the vehicle's scans matched against a
//! local map as they arrive, keyframes grouped into submaps, loop closures found against old
//! submaps and checked before they enter a pose graph, and an occupancy grid of the whole area
//! for people and planners. It runs scan by scan online and the same way over a recorded log.
#![forbid(unsafe_code)]

pub mod backend;
pub mod config;
pub mod correlative;
pub mod deskew;
pub mod estimated_motion;
pub mod graph;
pub mod grid;
pub mod guard;
pub mod keyframe;
pub mod loops;
pub mod map_files;
pub mod observed;
pub mod slam;
pub mod tracker;
pub mod worker;

pub use config::{EdgeNoise, GuardConfig, LoopConfig, SlamConfig};
pub use estimated_motion::EstimatedMotion;
pub use observed::Observed;
pub use slam::{Finished, ScanPose, Slam, TrackingStats, MAP_JUMP_M, MAP_JUMP_RAD};
pub use tracker::{local_map_cells, ConfigError};
