//! The onboard stack's side of `plumbline sim`: the options of the scenarios it flies, what it
//! did in the summary (modes, failsafe, motor jitter, the push's score), and its plots.

use super::outputs::create;
use super::plot::{stacked_panels, Line};
use crate::numeric::{within, Range};
use crate::plot::write_png;
use crate::report::CliError;
use clap::Args;
use plotters::prelude::*;
use plumbline_core::control::mrac::FallbackReason;
use plumbline_core::msgs::FailsafeReason;
use plumbline_sim::runner::companion::Strategy;
use plumbline_sim::runner::onboard_link::FlightLog;
use plumbline_sim::runner::{SimConfig, StateSample};
use plumbline_sim::scenario::score::OnboardScore;
use plumbline_sim::scenario::{Controller, Gains, Options, TrackShape, Tuning, GAIN_RANGES};
use serde_json::{json, Value};
use std::path::Path;

/// Options of the closed-loop scenarios.
#[derive(Args, Debug)]
pub struct ClosedLoopArgs {
    /// Who flies: `pid` (the onboard cascade; default for the closed-loop scenarios), `mrac`
    /// (the same cascade with model-reference adaptive control in place of its position and
    /// velocity loops) or `test-pilot` (the simulator's ground-truth pilot: `survey`,
    /// and `hold` as a sensor-log generator).
    #[arg(long, value_parser = ["pid", "mrac", "test-pilot"])]
    pub controller: Option<String>,
    /// PID gains: `aggressive` (the defaults) or `soft` (slower outer loops; seed 000's energy
    /// hypothesis compares the two).
    #[arg(long, default_value = "aggressive", value_parser = ["aggressive", "soft"])]
    pub tuning: String,
    /// Turn off the scan matcher's dynamic-object rejection (seed 000 sec. 4.2), to measure
    /// what the people in `hold-people` cost without it.
    #[arg(long)]
    pub no_rejection: bool,
    /// How `explore` chooses where to go: `frontier` (the nearest reachable edge of the known
    /// map, flown by the velocity field) or `wall-follow` (the velocity field and its heading
    /// rules alone).
    #[arg(long, default_value = "frontier", value_parser = ["frontier", "wall-follow"])]
    pub guidance: String,
    /// The path of `--scenario track`: a 3 m x 3 m `square` with a corner at the start, or a
    /// figure of `eight` in a 3 m x 3 m box centred on the start.
    #[arg(long, default_value = "square", value_parser = ["square", "eight"])]
    pub track: String,
    /// Position-loop gain replacing the tuning's (velocity setpoint per metre of error), 1/s.
    /// Valid range: [0.1, 5].
    #[arg(long, value_parser = within::<f32>(gain_range(0)))]
    pub position_kp: Option<f32>,
    /// Velocity-loop gain replacing the tuning's (acceleration per m/s of error), 1/s.
    /// Valid range: [0.5, 10].
    #[arg(long, value_parser = within::<f32>(gain_range(1)))]
    pub velocity_kp: Option<f32>,
    /// Velocity-loop integral gain replacing the tuning's, 1/s². Valid range: [0, 2].
    #[arg(long, value_parser = within::<f32>(gain_range(2)))]
    pub velocity_ki: Option<f32>,
    /// Time constant of a low-pass on the tilt command (0: none, the default), s: smoother
    /// motor commands, slower answer to a push. Valid range: [0, 1].
    #[arg(long, value_parser = within::<f32>(gain_range(3)))]
    pub command_tau: Option<f32>,
}

/// The valid range of the `i`-th entry of [`GAIN_RANGES`].
fn gain_range(i: usize) -> Range {
    let (_, lo, hi) = GAIN_RANGES[i];
    Range::closed(lo, hi)
}

impl ClosedLoopArgs {
    /// The scenario options these arguments and `--duration` ask for.
    pub fn options(&self, duration_s: Option<f64>) -> Options {
        let controller = self.controller.as_deref().map(|c| match c {
            "mrac" => Controller::Mrac,
            "test-pilot" => Controller::TestPilot,
            _ => Controller::Pid,
        });
        let tuning = match self.tuning.as_str() {
            "soft" => Tuning::Soft,
            _ => Tuning::Aggressive,
        };
        let strategy = match self.guidance.as_str() {
            "wall-follow" => Strategy::WallFollow,
            _ => Strategy::Frontier,
        };
        let track = match self.track.as_str() {
            "eight" => TrackShape::Eight,
            _ => TrackShape::Square,
        };
        Options {
            controller,
            tuning,
            gains: Gains {
                position_kp: self.position_kp,
                velocity_kp: self.velocity_kp,
                velocity_ki: self.velocity_ki,
                command_tau_s: self.command_tau,
            },
            dynamic_rejection: !self.no_rejection,
            duration_s,
            strategy,
            track,
        }
    }
}

fn fallback_name(r: FallbackReason) -> &'static str {
    match r {
        FallbackReason::NonFinite => "non_finite",
        FallbackReason::WeightBound => "weight_bound",
        FallbackReason::PersistentHedge => "persistent_hedge",
        FallbackReason::InvalidConfig => "invalid_config",
    }
}

/// Adds what the onboard stack did, and what only an onboard flight is scored on, to
/// `summary`.
pub fn extend_summary(
    summary: &mut Value,
    args: &ClosedLoopArgs,
    config: &SimConfig,
    log: &FlightLog,
    score: &OnboardScore,
) {
    let modes: Vec<Value> = log
        .modes
        .iter()
        .map(|(t, m)| json!({ "t_s": t, "mode": m.name() }))
        .collect();
    let extra = json!({
        "controller": args.controller.as_deref().unwrap_or("pid"),
        "tuning": args.tuning,
        "track": (summary["scenario"] == "track").then_some(args.track.as_str()),
        "position_kp": args.position_kp,
        "velocity_kp": args.velocity_kp,
        "velocity_ki": args.velocity_ki,
        "command_tau_s": args.command_tau,
        "dynamic_rejection": !args.no_rejection,
        "people": config.people,
        "landed": score.landed,
        "push_max_error_m": score.push_max_error_m,
        "recovery_s": score.recovery_s,
        "motor_jitter": log.motor_jitter(),
        "saturation_s": log.saturation_s,
        "mission_delay_s": log.mission_shift_s,
        "adaptive_weight_norm": log.adaptive_weight_norm,
        "max_adaptive_weight_norm": log.max_adaptive_weight_norm,
        "adaptive_fallback": log.adaptive_fallback.map(|(t_s, reason)| {
            json!({ "t_s": t_s, "reason": fallback_name(reason) })
        }),
        "failsafe": log.failsafe.map(FailsafeReason::name),
        "rejected_points": log.rejected_points,
        "modes": modes,
    });
    if let (Some(map), Value::Object(extra)) = (summary.as_object_mut(), extra) {
        map.extend(extra);
    }
}

/// `position_error.png` (seed 000 Fig. 9: Δx, Δy from the hold point, driven back to zero
/// after the push) and `motors.png` (the four motor commands). Altitude, roll, pitch, battery
/// and the top view are the command's `flight.png` and `top.png`.
pub fn plots(
    dir: &Path,
    config: &SimConfig,
    log: &FlightLog,
    states: &[StateSample],
) -> Result<(), CliError> {
    let start = [config.world.start[0], config.world.start[1]];
    let error = vec![(
        "position error from the hold point (m)",
        vec![
            (
                "dx",
                RED,
                states
                    .iter()
                    .map(|s| (s.t_s, s.position.x - start[0]))
                    .collect(),
            ),
            (
                "dy",
                BLUE,
                states
                    .iter()
                    .map(|s| (s.t_s, s.position.y - start[1]))
                    .collect(),
            ),
        ],
    )];
    write_png(create(dir, "position_error.png")?, |p| {
        stacked_panels(p, error)
    })?;
    let colors = [RED, GREEN, BLUE, BLACK];
    let names = ["motor 1", "motor 2", "motor 3", "motor 4"];
    let motors: Vec<Line> = (0..4)
        .map(|i| {
            let pts = log
                .samples
                .iter()
                .map(|s| (s.t_s, f64::from(s.motors[i])))
                .collect();
            (names[i], colors[i], pts)
        })
        .collect();
    write_png(create(dir, "motors.png")?, |p| {
        stacked_panels(p, vec![("motor commands (0..1)", motors)])
    })
}
