//! What every scenario flown by the onboard stack shares: the stack of `plumbline-core` built
//! for the vehicle and the lidar (through [`OnboardLink`]), the controller (PID or MRAC) and its
//! tuning, the matcher options, the run length and the pilot who arms it.

use super::flight::{Controller, Flight, Options, ScenarioError, Tuning};
use crate::disturb::Push;
use crate::runner::onboard_link::{
    autopilot_for, OnboardLink, Script, LARGE_SCAN_BEAMS, XV11_BEAMS,
};
use crate::runner::{Pilot, SetupError, SimConfig};
use plumbline_core::control::cascade::CascadeConfig;
use plumbline_core::flight::autopilot::AutopilotConfig;
use plumbline_core::flight::autopilot::ControllerKind;
use plumbline_core::matching::OdometryConfig;

/// The arm switch goes on here: the first half second lets the filter settle on the ground, s.
pub const ARM_AT_S: f64 = 0.5;
/// Run length when the options give none, s.
const DEFAULT_DURATION_S: f64 = 60.0;

/// Refuses controllers other than the onboard stack's (PID or MRAC) for `scenario`, and sets
/// the run length. The world's people stay out unless the scenario asks for them afterwards.
pub(super) fn setup(
    scenario: &'static str,
    options: &Options,
    config: &mut SimConfig,
) -> Result<(), ScenarioError> {
    if let Some(c) = options
        .controller
        .filter(|c| !matches!(c, Controller::Pid | Controller::Mrac))
    {
        return Err(ScenarioError::Controller {
            scenario,
            controller: c,
            reason: "this scenario exercises the onboard stack",
            instead: Some(Controller::Pid),
        });
    }
    config.max_duration_s = options.duration_s.unwrap_or(DEFAULT_DURATION_S);
    config.people = false;
    Ok(())
}

/// The onboard stack flying `config` as `script` says, scored on holding over the start
/// (`push` is the scenario's own, scored apart).
pub(super) fn flight(
    options: &Options,
    config: &SimConfig,
    script: Script,
    push: Option<Push>,
) -> Result<Flight, ScenarioError> {
    let (odometry, autopilot) = stack(options, config)?;
    let mission = script.mission.clone();
    let (pilot, log) = if config.lidar.beams <= XV11_BEAMS {
        let (link, log) =
            OnboardLink::<XV11_BEAMS>::new(&config.lidar, odometry, autopilot, script)
                .map_err(ScenarioError::Setup)?;
        (Pilot::Onboard(Box::new(link)), log)
    } else {
        let (link, log) =
            OnboardLink::<LARGE_SCAN_BEAMS>::new(&config.lidar, odometry, autopilot, script)
                .map_err(ScenarioError::Setup)?;
        (Pilot::Onboard(Box::new(link)), log)
    };
    Ok(Flight::onboard(pilot, log, push, mission, config))
}

/// The scan matcher and the autopilot as the options ask, for the vehicle of `config`.
pub(super) fn stack(
    options: &Options,
    config: &SimConfig,
) -> Result<(OdometryConfig, AutopilotConfig), ScenarioError> {
    let mut odometry = OdometryConfig::default();
    odometry.matcher.dynamic_rejection = options.dynamic_rejection;
    let mut autopilot = autopilot_for(&config.vehicle);
    if options.tuning == Tuning::Soft {
        // The airframe's hover collective and effectiveness stay; only the gains change.
        autopilot.cascade = CascadeConfig {
            hover_collective: autopilot.cascade.hover_collective,
            effectiveness_rad_s2: autopilot.cascade.effectiveness_rad_s2,
            ..CascadeConfig::soft()
        };
    }
    if options.controller == Some(Controller::Mrac) {
        autopilot.controller = ControllerKind::Mrac;
        autopilot
            .mrac
            .validate()
            .map_err(|e| ScenarioError::Setup(SetupError::Config(e.to_string())))?;
    }
    Ok((odometry, autopilot))
}
