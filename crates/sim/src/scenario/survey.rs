//! `survey`: the test pilot flies the world's path (take off, each leg turned into first, land),
//! scored on how closely it follows the plan. Its sensor logs are the simulator's benchmark
//! inputs.

use super::flight::{Controller, Entry, Flight, Options, ScenarioError};
use crate::runner::plan::{Plan, PlanLimits};
use crate::runner::SimConfig;
use crate::world::WorldError;

pub(super) const ENTRY: Entry = Entry {
    name: "survey",
    about: "the test pilot flies the world's path",
    prepare,
};

fn prepare(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    if let Some(c) = options.controller.filter(|c| *c != Controller::TestPilot) {
        return Err(ScenarioError::Controller {
            scenario: ENTRY.name,
            controller: c,
            reason: "it is flown by the test pilot (no onboard waypoint guidance yet)",
            instead: None,
        });
    }
    if config.world.path.is_empty() {
        return Err(ScenarioError::World(WorldError {
            line: 0,
            reason: format!("world {} has no survey path", config.world.name),
        }));
    }
    // The duration bounds the flight; the plan ends it.
    if let Some(d) = options.duration_s {
        config.max_duration_s = d;
    }
    let plan = Plan::survey(&config.world, PlanLimits::default());
    Ok(Flight::test_pilot(plan, config))
}
