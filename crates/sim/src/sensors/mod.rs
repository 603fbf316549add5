//! Emulated sensors. Each owns its own random stream (see [`crate::rng::Rng::fork`]) so that
//! turning one sensor on or off leaves the others' noise unchanged.

pub mod imu;
pub mod lidar;
pub mod sonar;
