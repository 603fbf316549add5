//! What a run needs ([`SimConfig`]) and the checks it passes before the first step.

use crate::disturb::{GustParams, Push};
use crate::runner::pilot::TestPilot;
use crate::sensors::imu::ImuParams;
use crate::sensors::lidar::LidarProfile;
use crate::sensors::sonar::SonarParams;
use crate::vehicle::model_error::ModelError;
use crate::vehicle::VehicleParams;
use crate::world::{World, WorldError};

/// Everything a run needs.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub world: World,
    /// The vehicle the onboard software is configured for (and the test pilot flies by).
    pub vehicle: VehicleParams,
    /// How the simulated body differs from `vehicle`; the onboard software is not told.
    pub model_error: ModelError,
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

/// Physics rates a run accepts, Hz: below 100 the fixed-step RK4 misses the motors' dynamics;
/// above 20 kHz a run costs 20 times the default for nothing, and 1e9 would never end.
pub const PHYSICS_HZ_RANGE: std::ops::RangeInclusive<f64> = 100.0..=20_000.0;

impl SimConfig {
    /// Defaults: f450 vehicle, ADIS16365 IMU, MB1040 sonar, indoor gusts, people on, 1 kHz.
    pub fn new(world: World, lidar: LidarProfile, seed: u64) -> Self {
        Self {
            world,
            vehicle: VehicleParams::f450(),
            model_error: ModelError::NONE,
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
        self.model_error.validate(v).map_err(SetupError::Vehicle)?;
        let start = [self.world.start[0], self.world.start[1]];
        self.world
            .check_free(start, v.radius_m, "start")
            .map_err(SetupError::World)?;
        if !PHYSICS_HZ_RANGE.contains(&self.physics_hz) {
            return Err(SetupError::Config(format!(
                "physics rate {} Hz is outside {} to {} Hz",
                self.physics_hz,
                PHYSICS_HZ_RANGE.start(),
                PHYSICS_HZ_RANGE.end()
            )));
        }
        TestPilot::new(v)
            .ok_or_else(|| SetupError::Config("rotor layout cannot be inverted".into()))
    }
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
