//! Lidar-only SLAM for the companion computer (std): the vehicle's scans matched against a
//! local map as they arrive, keyframes grouped into submaps, loop closures found against old
//! submaps and checked before they enter a pose graph, and an occupancy grid of the whole area
//! for people and planners. It runs scan by scan online and the same way over a recorded log.
#![forbid(unsafe_code)]

pub mod grid;
pub mod map_files;
