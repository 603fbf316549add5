//! Who flies: the test pilot on a plan, or onboard software behind the one step interface the
//! hardware has too.

use crate::runner::ground::GroundStation;
use crate::runner::plan::Plan;
use crate::sensors::lidar::LidarScan;
use plumbline_core::msgs::{BatterySample, ImuSample, MotorCommands, SonarSample};

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

    /// Links a ground station from the next step on; software without a ground link hands
    /// it back.
    fn link_ground(
        &mut self,
        station: Box<dyn GroundStation>,
    ) -> Result<(), Box<dyn GroundStation>> {
        Err(station)
    }
}

/// Who flies; `'a` bounds what the onboard software may borrow (a companion's SLAM borrows
/// its local map's cells from the caller).
pub enum Pilot<'a> {
    /// The ground-truth test pilot flying a scripted plan (simulator-only, see [`crate::runner::pilot`]).
    Test(Plan),
    /// Onboard code; the run lasts `SimConfig::max_duration_s`.
    Onboard(Box<dyn FlightSoftware + 'a>),
}
