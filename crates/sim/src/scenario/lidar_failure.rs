//! `lidar-failure`: the lidar stops delivering revolutions 10 s into the flight; the onboard
//! stack raises "lidar lost", holds on the IMU for a while, then lands.

use super::flight::{Entry, Flight, Options, ScenarioError};
use super::onboard::{self, ARM_AT_S};
use crate::runner::onboard_link::Script;
use crate::runner::SimConfig;

pub(super) const ENTRY: Entry = Entry {
    name: "lidar-failure",
    about: "the lidar stops at 10 s; hold on the IMU, then land",
    prepare,
};

/// The lidar stops delivering revolutions here, s.
pub const LIDAR_DIES_AT_S: f64 = 10.0;

fn prepare(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    onboard::setup(ENTRY.name, options, config)?;
    let script = Script {
        lidar_dies_at_s: Some(LIDAR_DIES_AT_S),
        ..Script::arm_at(ARM_AT_S)
    };
    onboard::flight(options, config, script, None)
}
