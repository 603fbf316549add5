//! `hold` and `hold-people` (seed 000 Fig. 8-9): the onboard stack takes off, holds 1 m over
//! the start on lidar odometry, and is pushed 2 N along world x for 1 s at t = 20 s; scored on
//! the hold error and the recovery. `hold-people` lets the world's people walk through the
//! scans. With the test pilot, `hold` is a sensor-log generator: it hovers over the start.

use super::flight::{Controller, Entry, Flight, Options, ScenarioError};
use super::onboard::{self, ARM_AT_S};
use crate::disturb::Push;
use crate::math::Vec3;
use crate::runner::onboard_link::Script;
use crate::runner::plan::{Plan, PlanLimits};
use crate::runner::SimConfig;

pub(super) const ENTRY: Entry = Entry {
    name: "hold",
    about: "hold 1 m over the start, pushed 2 N along x for 1 s at 20 s",
    prepare: hold,
};

pub(super) const WITH_PEOPLE: Entry = Entry {
    name: "hold-people",
    about: "hold, with the world's people walking through the scans",
    prepare: hold_people,
};

/// Seed 000's external force: 2 N along world x for 1 s at t = 20 s.
pub const PUSH: Push = Push {
    start_s: 20.0,
    duration_s: 1.0,
    force_n: Vec3::new(2.0, 0.0, 0.0),
};
/// How long the test pilot hovers when the options give no duration, s.
const TEST_PILOT_HOLD_S: f64 = 30.0;

fn hold(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    if options.controller == Some(Controller::TestPilot) {
        let hold_s = options.duration_s.unwrap_or(TEST_PILOT_HOLD_S);
        let plan = Plan::hold(&config.world, PlanLimits::default(), hold_s);
        return Ok(Flight::test_pilot(plan, config));
    }
    onboard::setup(ENTRY.name, options, config)?;
    pushed_hold(options, config)
}

fn hold_people(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    // The people walk unless the caller left them out.
    let people = config.people;
    onboard::setup(WITH_PEOPLE.name, options, config)?;
    config.people = people;
    pushed_hold(options, config)
}

fn pushed_hold(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    config.pushes.push(PUSH);
    onboard::flight(options, config, Script::arm_at(ARM_AT_S), Some(PUSH))
}
