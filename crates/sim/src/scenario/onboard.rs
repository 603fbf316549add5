//! What every scenario flown by the onboard stack shares: the stack of `plumbline-core` built
//! for the vehicle and the lidar (through [`OnboardLink`]), the controller (PID or MRAC) and its
//! tuning, the matcher options, the run length and the pilot who arms it.

use super::flight::{Controller, Flight, Gains, Options, ScenarioError, Tuning};
use crate::disturb::Push;
use crate::runner::onboard_link::{
    autopilot_for, OnboardLink, Script, LARGE_SCAN_BEAMS, XV11_BEAMS,
};
use crate::runner::{Pilot, SetupError, SimConfig};
use plumbline_core::control::cascade::CascadeConfig;
use plumbline_core::flight::autopilot::{AutopilotConfig, ControllerKind};
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
    let mut odometry = OdometryConfig::in_flight();
    odometry.matcher.dynamic_rejection = options.dynamic_rejection;
    let mut autopilot = autopilot_for(&config.vehicle);
    if options.tuning == Tuning::Soft {
        // The airframe's hover collective and effectiveness stay; only the gains change.
        let c = &autopilot.cascade;
        autopilot.cascade =
            CascadeConfig::soft().fitted(c.hover_collective, c.effectiveness_rad_s2);
    }
    if options.controller == Some(Controller::Mrac) {
        autopilot.controller = ControllerKind::Mrac;
        autopilot
            .mrac
            .validate()
            .map_err(|e| ScenarioError::Setup(SetupError::Config(e.to_string())))?;
    }
    apply_gains(&mut autopilot, &options.gains)?;
    Ok((odometry, autopilot))
}

/// Replaces the outer-loop gains of the controller that flies, and the command filter, with
/// those `gains` sets. The MRAC takes them as its reference model's (the PID's loop gains) and
/// its PD on the model's error in the same stiffness (`kp = position x velocity`, `kd =
/// velocity`, as its defaults relate to the PID's); it has no velocity integral to set.
fn apply_gains(autopilot: &mut AutopilotConfig, gains: &Gains) -> Result<(), ScenarioError> {
    let refuse = |e: String| ScenarioError::Setup(SetupError::Config(e));
    gains.check().map_err(refuse)?;
    let c = &mut autopilot.cascade;
    c.command_tau_s = gains.command_tau_s.unwrap_or(c.command_tau_s);
    if autopilot.controller == ControllerKind::Mrac {
        if gains.velocity_ki.is_some() {
            return Err(refuse(
                "velocity_ki sets the PID's velocity integral; the mrac has none".into(),
            ));
        }
        let (r, pd) = (&mut autopilot.mrac.reference_xy, &mut autopilot.mrac.pd_xy);
        r.position_gain_per_s = gains.position_kp.unwrap_or(r.position_gain_per_s);
        r.velocity_gain_per_s = gains.velocity_kp.unwrap_or(r.velocity_gain_per_s);
        if gains.position_kp.is_some() || gains.velocity_kp.is_some() {
            pd.kp_per_s2 = r.position_gain_per_s * r.velocity_gain_per_s;
            pd.kd_per_s = r.velocity_gain_per_s;
        }
        return autopilot.mrac.validate().map_err(|e| refuse(e.to_string()));
    }
    c.position_xy.kp = gains.position_kp.unwrap_or(c.position_xy.kp);
    let v = &mut c.velocity_xy;
    v.kp = gains.velocity_kp.unwrap_or(v.kp);
    v.ki = gains.velocity_ki.unwrap_or(v.ki);
    Ok(())
}
