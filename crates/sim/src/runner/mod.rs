//! The run: the lockstep runner (this module and `lockstep`), who flies ([`pilot`], the
//! ground-truth test pilot, flying a [`plan`]; or the onboard stack through [`onboard_link`],
//! perhaps on a [`mission`]),
//! and the ground-truth relations between scans ([`truth`]).
//!
//! The lockstep runner: one fixed physics step at a time (default 1 kHz), sensors sampled at
//! their own rates inside it, and the flight software called at its own rate through one step
//! interface (DESIGN.md §1). Everything random draws from streams forked from one seed, and
//! nothing reads a clock, so a run is reproducible bit for bit.
//!
//! [`run`] is the loop; one step of it is `lockstep`'s, with the run's state between steps.

mod config;
mod fix_covariance;
mod landing_spot;
pub mod ground;
mod lockstep;
pub mod companion;
pub mod crew;
pub mod mission;
pub mod onboard_link;
pub mod pilot;
pub mod plan;
mod progress;
mod report;
mod software;
pub mod truth;

pub use config::{SetupError, SimConfig, PHYSICS_HZ_RANGE};
pub use report::{
    Discard, Outcome, Recorder, StateSample, Status, TruthPose, CLEARANCE_CAP_M, STATE_RATE_HZ,
};
pub use software::{FlightSoftware, Pilot, SensorFrame};

use lockstep::Lockstep;

/// Flies one run to the end and reports it: the lockstep loop of physics, sensors and pilot
/// (see `Lockstep::step`) until the flight's end or the first crash.
pub fn run<'a>(
    config: &'a SimConfig,
    pilot: Pilot<'a>,
    recorder: &mut dyn Recorder,
) -> Result<Outcome, SetupError> {
    let (mut sim, mut dynamics, mut body) = Lockstep::new(config, pilot)?;
    // The body changes at most once (a payload's release): the dynamics are rebuilt then,
    // so the step itself never asks whether its constants are still right.
    let mut change = sim.body_change_step();
    while sim.running() {
        if change == Some(sim.steps()) {
            change = None;
            dynamics = sim.dynamics_after_change();
        }
        if let Err(end) = sim.step(&dynamics, &mut body, recorder) {
            return Ok(sim.finish(end));
        }
    }
    Ok(sim.finish(Status::Completed))
}
