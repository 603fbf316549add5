//! Exploration for the companion computer (std): the occupancy grid kept current from the
//! online SLAM, the nearest reachable frontier and a path to it over a map whose obstacles are
//! grown by the vehicle's clearance, a lookahead waypoint for the velocity field, the decision
//! that exploring is done, and the way home with its length.
#![forbid(unsafe_code)]

pub mod blind;
pub mod config;
pub mod explorer;
pub mod frontier;
pub mod live_map;
pub mod path;
pub mod plan_grid;
pub mod search;

pub use blind::BlindBudget;
pub use config::{ConfigError, ExploreConfig};
pub use explorer::{DoneReason, ExploreStats, ExploreStep, Explorer};
pub use live_map::{LiveMap, MapUpdate};
pub use path::Path;
