//! Plumbline's quadrotor simulator (f64): worlds, rigid-body dynamics, motors, battery,
//! emulated sensors, disturbances and the lockstep runner that drives the onboard code.
#![forbid(unsafe_code)]

pub mod battery;
pub mod disturb;
pub mod dynamics;
pub mod math;
pub mod occupancy;
pub mod pilot;
pub mod plan;
pub mod power;
pub mod rng;
pub mod runner;
pub mod scene;
pub mod sensors;
pub mod truth;
pub mod vehicle;
pub mod world;
