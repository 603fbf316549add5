//! Seed 002's wall-following guidance (sec. II.B.1): wall segments by polar recursive least
//! squares, the velocity field of eqs. 1-3, the heading and gap rules, and a waypoint mode
//! that keeps the field's clearance while a planner chooses the way.
//!
//! Pure and heap-free: [`Guidance::step`] takes one revolution and the estimated pose and
//! returns a world-frame velocity and heading plus what the rules decided. It knows nothing of
//! flight modes; the autopilot or a companion computer calls it once per revolution.

pub mod config;
pub mod field;
pub mod gaps;
pub mod guard;
pub mod heading;
pub mod prls;
mod run;
pub mod step;
mod sweep;

pub use config::{GuidanceConfig, GuidanceConfigError};
pub use guard::Guard;
pub use heading::HeadingRule;
pub use prls::{Gap, WallSegment, WallSegments};
pub use step::{Decision, Guidance, GuidanceCommand, GuidanceMode, Outcome};
