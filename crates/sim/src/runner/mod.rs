//! The lockstep runner: one fixed physics step at a time (default 1 kHz), sensors sampled at
//! their own rates inside it, and the flight software called at its own rate through one step
//! interface (DESIGN.md §1). Everything random draws from streams forked from one seed, and
//! nothing reads a clock, so a run is reproducible bit for bit.
//!
//! [`run`] is the loop; one step of it is [`lockstep`]'s, with the run's state between steps.

use crate::disturb::{GustParams, Push};
use crate::math::{Quat, Vec3};
use crate::pilot::TestPilot;
use crate::plan::Plan;
use crate::power::EnergyTally;
use crate::sensors::imu::ImuParams;
use crate::sensors::lidar::{LidarProfile, LidarScan};
use crate::sensors::sonar::SonarParams;
use crate::vehicle::VehicleParams;
use crate::world::{World, WorldError};
use lockstep::Lockstep;
use plumbline_core::msgs::{BatterySample, ImuSample, MotorCommands, SonarSample};

mod lockstep;

/// Everything a run needs.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub world: World,
    pub vehicle: VehicleParams,
    pub lidar: LidarProfile,
    pub imu: ImuParams,
    pub sonar: SonarParams,
    pub gusts: Option<GustParams>,
    pub pushes: Vec<Push>,
    /// Whether the world's walking people are present.
    pub people: bool,
    pub physics_hz: f64,
    pub seed: u64,
    /// Stop after this much simulated time even if the flight is not over, s.
    pub max_duration_s: f64,
}

impl SimConfig {
    /// Defaults: f450 vehicle, ADIS16365 IMU, MB1040 sonar, indoor gusts, people on, 1 kHz.
    pub fn new(world: World, lidar: LidarProfile, seed: u64) -> Self {
        Self {
            world,
            vehicle: VehicleParams::f450(),
            lidar,
            imu: ImuParams::adis16365(),
            sonar: SonarParams::mb1040(),
            gusts: Some(GustParams::indoor()),
            pushes: Vec::new(),
            people: true,
            physics_hz: 1000.0,
            seed,
            max_duration_s: 3600.0,
        }
    }
}

impl SimConfig {
    /// Checks everything a run needs before it starts: the vehicle, a start the vehicle fits
    /// at, the physics rate. Returns the test pilot for the vehicle (its rotor layout must be
    /// invertible). Callers that write files check first, so a refused run leaves none.
    pub fn validate(&self) -> Result<TestPilot, SetupError> {
        let v = &self.vehicle;
        v.validate().map_err(SetupError::Vehicle)?;
        let start = [self.world.start[0], self.world.start[1]];
        self.world
            .check_free(start, v.radius_m, "start")
            .map_err(SetupError::World)?;
        if !(self.physics_hz.is_finite() && self.physics_hz >= 100.0) {
            return Err(SetupError::Config(format!(
                "physics rate {} Hz is below 100 Hz",
                self.physics_hz
            )));
        }
        TestPilot::new(v)
            .ok_or_else(|| SetupError::Config("rotor layout cannot be inverted".into()))
    }
}

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
    pub power_w: f64,
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

/// What arrived since the flight software's previous step.
#[derive(Clone, Copy, Debug)]
pub struct SensorFrame<'a> {
    pub t_s: f64,
    pub imu: &'a [ImuSample],
    pub sonar: Option<SonarSample>,
    pub scans: &'a [LidarScan],
    pub battery: BatterySample,
}

/// The onboard software as the simulator drives it: the same `step(inputs, dt) -> outputs`
/// shape as on hardware. It never sees ground truth.
pub trait FlightSoftware {
    fn rate_hz(&self) -> f64;
    fn step(&mut self, sensors: &SensorFrame<'_>, dt_s: f64) -> MotorCommands;
}

/// Who flies.
pub enum Pilot {
    /// The ground-truth test pilot flying a scripted plan (simulator-only, see [`crate::pilot`]).
    Test(Plan),
    /// Onboard code; the run lasts `SimConfig::max_duration_s`.
    Onboard(Box<dyn FlightSoftware>),
}

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
}

/// Setup errors, reported before the first step.
#[derive(Clone, Debug, PartialEq)]
pub enum SetupError {
    World(WorldError),
    Vehicle(crate::vehicle::ParamError),
    Config(String),
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SetupError::World(e) => write!(f, "world: {e}"),
            SetupError::Vehicle(e) => write!(f, "{e}"),
            SetupError::Config(s) => write!(f, "{s}"),
        }
    }
}

impl std::error::Error for SetupError {}

/// Clearance is searched only this far (grid cells around the vehicle), m.
pub const CLEARANCE_CAP_M: f64 = 2.0;

/// Flies one run to the end and reports it: the lockstep loop of physics, sensors and pilot
/// (see [`Lockstep::step`]) until the flight's end or the first crash.
pub fn run(
    config: &SimConfig,
    pilot: Pilot,
    recorder: &mut dyn Recorder,
) -> Result<Outcome, SetupError> {
    let (mut sim, mut body) = Lockstep::new(config, pilot)?;
    while sim.running() {
        if let Err(end) = sim.step(&mut body, recorder) {
            return Ok(sim.finish(end));
        }
    }
    Ok(sim.finish(Status::Completed))
}
