//! What a run reports: the samples and the truth as they are produced (to a [`Recorder`]), and
//! its figures at the end ([`Outcome`]).

use crate::math::{Quat, Vec3};
use crate::sensors::lidar::LidarScan;
use crate::vehicle::power::EnergyTally;
use crate::vehicle::still_hover::StillHover;
use plumbline_core::msgs::{ImuSample, SonarSample};

/// The true 3-D pose of the vehicle at an instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthPose {
    pub t_s: f64,
    pub position: Vec3,
    pub attitude: Quat,
}

/// A snapshot for plots and progress, taken at [`STATE_RATE_HZ`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateSample {
    pub t_s: f64,
    pub position: Vec3,
    pub reference: Option<Vec3>,
    /// Roll, pitch, yaw, rad.
    pub euler: [f64; 3],
    pub battery_v: f64,
    /// Electrical power at this physics step, W.
    pub power_w: f64,
    /// Energy drawn since the start, integrated at every physics step, Wh: the difference of
    /// two samples is the exact energy between them, which a mean of the sampled powers is not.
    pub energy_wh: f64,
    /// Rotor speeds Ω_i, rad/s.
    pub rotor_speed: [f64; 4],
    /// Total rotor thrust along body z, N.
    pub thrust_n: f64,
}

pub const STATE_RATE_HZ: f64 = 50.0;

/// Receives the sensor streams and ground truth as they are produced.
pub trait Recorder {
    fn scan(&mut self, _scan: &LidarScan, _truth: &TruthPose) {}
    fn imu(&mut self, _sample: &ImuSample) {}
    fn sonar(&mut self, _sample: &SonarSample) {}
    fn state(&mut self, _sample: &StateSample) {}
    /// At every step of the test pilot: the true position and where its plan wants the
    /// vehicle (scenarios score the tracking from these).
    fn tracking(&mut self, _t_s: f64, _position: Vec3, _reference: Vec3) {}
}

/// A recorder that keeps nothing (benchmarks, tests that only need the outcome).
pub struct Discard;
impl Recorder for Discard {}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Completed,
    Crashed { t_s: f64, reason: String },
    Diverged { t_s: f64 },
    BatteryExhausted { t_s: f64 },
}

/// The figures of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub status: Status,
    pub sim_seconds: f64,
    pub physics_steps: u64,
    pub scans: u64,
    pub energy: EnergyTally,
    /// Energy drawn from the cells (includes the pack's internal loss), Wh.
    pub battery_energy_wh: f64,
    pub battery_end_v: f64,
    pub battery_min_v: f64,
    pub battery_end_soc: f64,
    /// First time the loaded pack voltage fell below the low threshold, s.
    pub battery_low_at_s: Option<f64>,
    /// Smallest distance from the centre to a wall, capped at [`CLEARANCE_CAP_M`].
    pub min_clearance_m: f64,
    pub distance_flown_m: f64,
    /// The body's still hover at the start (see [`StillHover`]): the floor under the mean
    /// power of a flight that holds its place. `None` when the body cannot hover balanced.
    pub still_hover: Option<StillHover>,
}

/// Clearance is searched only this far (grid cells around the vehicle), m.
pub const CLEARANCE_CAP_M: f64 = 2.0;
