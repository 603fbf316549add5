//! Seed 002's wall-following guidance (sec. II.B.1): wall segments by polar recursive least
//! squares, the velocity field of eqs. 1-3, the heading and gap rules, and a waypoint mode
//! that keeps the field's clearance while a planner chooses the way.
//!
//! Pure and heap-free: [`Guidance::step`] takes one revolution and the estimated pose and
//! returns a world-frame velocity and heading plus what the rules decided. It knows nothing of
//! flight modes; the autopilot or a companion computer calls it once per revolution. Memory:
//! `size_of::<Guidance<S>>()` (about 15.5 KB for 64 segments: 4.5 KB of it the near-hit memory,
//! 3.3 KB the previous revolution's hits by bearing, for finding movers) plus about 11 KB of
//! stack a step for a 360-beam scan.
//!
//! Walking people: a surface that closes in between revolutions faster than a wall's noise
//! allows is a mover ([`movers`]); one that would reach `r_min` within `evade_horizon_s` is
//! stepped aside from by a velocity obstacle over guarded candidates ([`evade`]), so walls
//! keep `r_min` while the vehicle gets out of the walker's way.
//!
//! Safety: whatever the rules and the field ask, the last stage ([`guard`]) limits the speed
//! toward every hit to `approach_rate · (r − r_min)`, so no command closes on a wall inside
//! `r_min`; hits within the guard's reach are remembered for `obstacle_memory_s`, and while
//! the vehicle stays within its stopping distance of where it saw them for up to
//! `obstacle_hold_s`, so a wall end the lidar loses at a grazing angle still counts. A featureless corridor is flown
//! centred, along the wall's direction.
//!
//! Degraded input: no usable beam, a non-finite pose or waypoint give a hover (zero velocity,
//! heading held) with the reason in [`Outcome`]; more segments than `S` keep the first `S`.
//!
//! Limits: a gap's width is measured between hits, so it exceeds the true opening by up to a
//! beam spacing at each edge (the default threshold leaves 0.3 m over the vehicle's width);
//! with a lidar that does not see all round, an opening whose far side lies in the blind
//! sector is measured only from the side that is seen.

pub mod config;
pub mod evade;
pub mod field;
pub mod gaps;
pub mod guard;
pub mod heading;
mod memory;
pub mod movers;
pub mod nearest_hits;
pub mod prls;
mod run;
pub mod step;
mod sweep;

pub use config::{GuidanceConfig, GuidanceConfigError};
pub use guard::{ApproachLimit, Guard};
pub use heading::HeadingRule;
pub use movers::Mover;
pub use prls::{Gap, WallSegment, WallSegments};
pub use step::{Decision, Guidance, GuidanceCommand, GuidanceMode, Outcome};
