//! Plumbline's quadrotor simulator (f64): worlds, rigid-body dynamics, motors, battery,
//! emulated sensors, disturbances, the scenarios and the lockstep runner that drives the
//! onboard code.
//!
//! Its rooms, by what they model:
//! - [`world`]: the world and its geometry (walls, blocks, people, occupancy grids, ray casting);
//! - [`vehicle`]: the vehicle (parameters, rigid-body dynamics, motors, battery, power);
//! - [`sensors`]: the emulated lidar, IMU and sonar;
//! - [`disturb`]: disturbances (turbulence, pushes);
//! - [`runner`]: the run (the lockstep loop, the test pilot and its plans, the link to the
//!   onboard stack, ground-truth relations);
//! - [`scenario`]: what a flight is for and how it is scored;
//! - [`math`] and [`rng`]: the vectors and the seeded randomness everything shares.
//!
//! A run: a [`world::World`] (parsed, shipped, or from an [`world::occupancy::Occupancy`] grid),
//! a [`runner::SimConfig`] (vehicle preset, lidar profile, IMU, sonar, gusts, pushes, seed), and
//! a scenario from [`scenario::CATALOGUE`] that sets it up and chooses who flies;
//! [`scenario::fly`] runs it through [`runner::run`], hands every sensor sample and the truth
//! to a [`runner::Recorder`], and scores the flight. The `plumbline sim` command writes all of
//! it to files.
#![forbid(unsafe_code)]

pub mod disturb;
pub mod map_error;
pub mod math;
pub mod rng;
pub mod runner;
pub mod scenario;
pub mod sensors;
pub mod vehicle;
pub mod world;
