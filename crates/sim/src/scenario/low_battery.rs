//! `land-on-low-battery`: the onboard stack takes off on a nearly empty pack and must land
//! when the loaded voltage falls below its threshold, before the pack is exhausted.

use super::flight::{Entry, Flight, Options, ScenarioError};
use super::onboard::{self, ARM_AT_S};
use crate::runner::onboard_link::Script;
use crate::runner::SimConfig;

pub(super) const ENTRY: Entry = Entry {
    name: "land-on-low-battery",
    about: "take off on a nearly empty pack; the low-battery failsafe lands",
    prepare,
};

/// Charge at take-off, chosen so that the loaded pack falls below the landing threshold
/// (3.5 V per cell) about 10 s into the hold.
const LOW_BATTERY_SOC: f64 = 0.12;

fn prepare(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    onboard::setup(ENTRY.name, options, config)?;
    config.vehicle.battery.initial_soc = LOW_BATTERY_SOC;
    onboard::flight(options, config, Script::arm_at(ARM_AT_S), None)
}
