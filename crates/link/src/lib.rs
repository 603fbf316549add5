//! Plumbline's MAVLink 2 link (common dialect), transport-free: bytes in, bytes out.
//!
//! The onboard code keeps its plain message structs; this crate is the only place that knows
//! the wire format. A [`Link`] turns the vehicle's state into telemetry frames at documented
//! rates ([`telemetry`]), incoming frames into core's [`GroundCommand`]s, ground heartbeats and
//! parameter requests ([`InboundEvent`]) — and on a companion computer's link its autopilot's
//! estimate ([`EstimateWatch`]) — answers with COMMAND_ACK, PARAM_VALUE and
//! PARAM_ERROR, signs and checks signatures with a key, and counts everything it refuses
//! ([`DropCounters`]). It owns no socket and reads no clock: the simulator, the companion
//! computer and the fuzzers drive the same code and a run replays exactly.
//!
//! Frames: NED/FRD on the wire, ENU/FLU inside, converted only in [`ned`].
//!
//! [`GroundCommand`]: plumbline_core::msgs::GroundCommand
#![forbid(unsafe_code)]

mod commands;
mod counters;
mod crc;
mod estimate_in;
mod estimate_watch;
mod link;
pub mod modes;
pub mod ned;
mod obstacle;
mod odometry;
mod param_replies;
mod params;
mod scanner;
mod signing;
pub mod telemetry;
mod wire;

pub use commands::AckTo;
pub use counters::DropCounters;
pub use estimate_in::{estimate_sample, EstimatePart, EstimateSample, OdometryPose};
pub use estimate_watch::{EstimateWatch, Withheld};
pub use link::{
    InboundEvent, Link, LinkConfig, LinkTime, Peer, COMPONENT_AUTOPILOT, COMPONENT_ONBOARD_COMPUTER,
};
/// The `mavlink` crate's common dialect, for callers that build other messages.
pub use mavlink::dialects::common;
pub use obstacle::{obstacle_distance, sector_of, ObstacleRange, SECTORS};
pub use odometry::{odometry_from_estimate, odometry_from_pose_fix};
pub use params::{ParamName, ParamRef, ParamRequest, ParameterStore, NAME_LEN};
pub use scanner::frame_span;
pub use signing::{timestamp_from_unix, SigningKey};
pub use telemetry::{SensorRanges, TelemetryInput, TelemetryRates};
