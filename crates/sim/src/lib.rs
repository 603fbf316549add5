//! Plumbline's quadrotor simulator (f64): worlds, rigid-body dynamics, motors, battery,
//! emulated sensors, disturbances and the lockstep runner that drives the onboard code.
//!
//! A run: a [`world::World`] (parsed, shipped, or from an [`occupancy::Occupancy`] grid), a
//! [`runner::SimConfig`] (vehicle preset, lidar profile, IMU, sonar, gusts, pushes, seed), and a
//! [`runner::Pilot`]: either the ground-truth test pilot flying a [`plan::Plan`], or onboard code
//! behind [`runner::FlightSoftware`]. [`runner::run`] steps the physics at a fixed rate and hands
//! every sensor sample and the truth to a [`runner::Recorder`]; [`truth::relations`] turns the
//! scan poses into Freiburg relations. The `plumbline sim` command writes all of it to files.
#![forbid(unsafe_code)]

pub mod battery;
pub mod clearance;
pub mod disturb;
pub mod dynamics;
pub mod math;
pub mod motors;
pub mod nearby;
pub mod occupancy;
pub mod onboard_link;
pub mod pilot;
pub mod plan;
pub mod power;
pub mod rng;
pub mod runner;
pub mod scenario;
pub mod scene;
pub mod sensors;
pub mod truth;
pub mod vehicle;
pub mod world;
pub mod ziggurat;
