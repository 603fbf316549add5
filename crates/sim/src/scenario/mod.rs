//! Scenarios: what a simulated flight is for and how it is judged. Each scenario sets up a run
//! (the world is the caller's; the scenario adds pushes, faults, a battery state, a script for
//! the pilot's radio) and chooses who flies; [`fly`] runs it and scores the flight against
//! ground truth in one place ([`score`]).
//!
//! The catalogue:
//! - `survey` ([`survey`]): the test pilot flies the world's path (sensor logs for the
//!   benchmarks).
//! - `hold`, `hold-people` ([`hold`]): the onboard stack takes off, holds 1 m over the start and
//!   rides out seed 000's push; `hold-people` lets the world's people walk.
//! - `land-on-low-battery` ([`low_battery`]): a nearly empty pack must bring the vehicle down.
//! - `lidar-failure` ([`lidar_failure`]): the lidar stops; the vehicle holds on the IMU, then
//!   lands.
//! - `explore` ([`explore`]): the vehicle explores the world on its SLAM map with its
//!   companion computer, comes home and lands; scored on what it saw ([`coverage`],
//!   [`explore_score`]).
//! - `track` ([`track`]): the onboard stack flies a square or a figure of eight fed to it as
//!   mission setpoints; scored on the tracking error.
//!
//! Adding a scenario is one new file and one catalogue entry: write `scenario/NAME.rs` with a
//! `pub(super) const ENTRY: Entry` (its parts come from `super::flight`) whose `prepare`
//! adjusts the [`SimConfig`](crate::runner::SimConfig) and returns the [`Flight`]: the test
//! pilot with a [`Plan`](crate::runner::plan::Plan) ([`Flight::test_pilot`]), or the onboard
//! stack (`onboard::setup` and `onboard::flight` do the common part). Then declare the module
//! here and add `NAME::ENTRY` to [`CATALOGUE`]. Scoring needs no new code unless the scenario
//! judges something new: then it goes in [`score`], next to the rest.

pub mod coverage;
mod explore;
pub mod explore_score;
mod flight;
pub mod hold;
pub mod lidar_failure;
pub mod low_battery;
pub mod onboard;
pub mod score;
pub mod survey;
pub mod track;

pub use flight::{
    fly, Controller, Entry, Flight, Gains, Options, Report, ScenarioError, Tuning, GAIN_RANGES,
};
pub use track::TrackShape;

/// Every scenario, as named on the command line.
pub static CATALOGUE: [Entry; 7] = [
    survey::ENTRY,
    hold::ENTRY,
    hold::WITH_PEOPLE,
    low_battery::ENTRY,
    lidar_failure::ENTRY,
    explore::ENTRY,
    track::ENTRY,
];

/// The scenario called `name`.
pub fn find(name: &str) -> Option<&'static Entry> {
    CATALOGUE.iter().find(|e| e.name == name)
}
