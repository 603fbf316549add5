//! `plumbline study energy`: seed 000 sec. 5.3's question (does smoother control spend less
//! energy?) put to the simulator. Every combination of the outer-loop gains and the tilt command
//! filter is flown in the room's hold scenario (its push, and its people for `hold-people`) over
//! several seeds; the table, the Pareto plot of energy per minute against RMS hold error and
//! the power breakdown beside seed 000 Fig. 12 go to `--out`.

use super::pareto::{self, Point};
use super::{energy_plot, energy_table, excess_plot};
use crate::numeric::{within, Range};
use crate::plot::write_png;
use crate::report::{print_summary, CliError, CliResult};
use crate::sim::load_world;
use clap::Args;
use plumbline_core::control::cascade::CascadeConfig;
use plumbline_core::msgs::FlightMode;
use plumbline_io::output::{self, OutputFile};
use plumbline_sim::runner::{Recorder, SimConfig, StateSample, Status};
use plumbline_sim::scenario::score::SETTLE_S;
use plumbline_sim::scenario::{self, Controller, Gains, Options, GAIN_RANGES};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::vehicle::dynamics::Dynamics;
use plumbline_sim::vehicle::hover_excess::{hover_excess, HoverExcess};
use plumbline_sim::vehicle::still_hover::StillHover;
use plumbline_sim::vehicle::VehicleParams;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The question's thresholds: within 10 % of the default's hold error, on 10 % less energy.
const ERROR_SLACK: f64 = 0.1;
const ENERGY_SAVING: f64 = 0.1;

#[derive(Args, Debug)]
pub struct EnergyArgs {
    /// Directory for energy.tsv, summary.json, pareto.png, power.png and excess.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Controllers to sweep, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "pid", value_parser = ["pid", "mrac"])]
    pub controller: Vec<String>,
    /// Scenario each setting flies (`hold-people` adds the world's walking people).
    #[arg(long, default_value = "hold", value_parser = ["hold", "hold-people"])]
    pub scenario: String,
    /// Position-loop gains to sweep, comma separated, 1/s. Valid range: [0.1, 5].
    #[arg(long, value_delimiter = ',', default_value = "0.5,1,1.5,2,3",
          value_parser = within::<f32>(gain_range(0)))]
    pub position_kp: Vec<f32>,
    /// Velocity-loop gains to sweep, comma separated, 1/s. Valid range: [0.5, 10].
    #[arg(long, value_delimiter = ',', default_value = "2,3,4,6",
          value_parser = within::<f32>(gain_range(1)))]
    pub velocity_kp: Vec<f32>,
    /// Tilt command filter time constants to sweep, comma separated, s (0: none).
    /// Valid range: [0, 1].
    #[arg(long, value_delimiter = ',', default_value = "0,0.05,0.15,0.4",
          value_parser = within::<f32>(gain_range(3)))]
    pub command_tau: Vec<f32>,
    /// Seeds per setting (SEED, SEED+1, ...). Valid range: [1, 1000].
    #[arg(long, default_value_t = 5, value_parser = within::<u32>(Range::closed(1.0, 1000.0)))]
    pub seeds: u32,
    /// The first seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Length of each flight, s. Valid range: (5, 3600].
    #[arg(long, default_value_t = 60.0, value_parser = within::<f64>(Range::above(5.0, 3600.0)))]
    pub duration: f64,
    /// Flights run at once (default: the machine's cores). Valid range: [1, 256].
    #[arg(long, value_parser = within::<u32>(Range::closed(1.0, 256.0)))]
    pub threads: Option<u32>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The valid range of the `i`-th entry of [`GAIN_RANGES`].
fn gain_range(i: usize) -> Range {
    let (_, lo, hi) = GAIN_RANGES[i];
    Range::closed(lo, hi)
}

/// One setting of the sweep: a controller and the gains replacing its defaults (none: the
/// default itself).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setting {
    pub controller: Controller,
    pub gains: Gains,
}

/// One flight's figures.
#[derive(Clone, Copy, Debug)]
struct Run {
    /// `None` when the flight crashed or never held.
    error_m: Option<f64>,
    /// Per minute of flight, Wh/min: motors, ESCs, avionics.
    parts_wh_min: [f64; 3],
    /// Mean electrical power over the scored hold (from the settling after Hold is entered to
    /// the end), from the energy integrated at every physics step, W.
    hold_power_w: f64,
    /// The hold's mean power above the flown body's still hover, and why.
    excess: HoverExcess,
    jitter: f64,
}

/// Keeps the state samples of a flight (50 Hz), for the hold phase's power and its excess
/// over the still hover.
#[derive(Default)]
struct StateSamples(Vec<StateSample>);

impl Recorder for StateSamples {
    fn state(&mut self, s: &StateSample) {
        self.0.push(*s);
    }
}

/// A setting's means over its seeds.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    pub setting: Setting,
    /// Hold error and hold-phase energy per minute; the error is NaN when any seed crashed
    /// or never held.
    pub point: Point,
    /// Whole flight (ground, takeoff, hold), per minute: motors, ESCs, avionics, Wh/min.
    pub parts_wh_min: [f64; 3],
    pub hold_power_w: f64,
    pub excess: HoverExcess,
    pub jitter: f64,
    pub failed: usize,
}

fn controller(name: &str) -> Controller {
    match name {
        "mrac" => Controller::Mrac,
        _ => Controller::Pid,
    }
}

/// The default of each controller first, then every grid combination that differs from it.
pub fn settings(args: &EnergyArgs) -> Vec<Setting> {
    let d = CascadeConfig::default();
    let mut out = Vec::new();
    for c in &args.controller {
        let controller = controller(c);
        out.push(Setting {
            controller,
            gains: Gains::default(),
        });
        for &p in &args.position_kp {
            for &v in &args.velocity_kp {
                for &tau in &args.command_tau {
                    if (p, v, tau) == (d.position_xy.kp, d.velocity_xy.kp, d.command_tau_s) {
                        continue;
                    }
                    out.push(Setting {
                        controller,
                        gains: Gains {
                            position_kp: Some(p),
                            velocity_kp: Some(v),
                            velocity_ki: None,
                            command_tau_s: Some(tau),
                        },
                    });
                }
            }
        }
    }
    out
}

/// Flies `setting` with `seed` in the room.
fn fly(args: &EnergyArgs, setting: Setting, seed: u64) -> Result<Run, CliError> {
    let world = load_world("room")?;
    let lidar = LidarProfile::by_name("xv11").ok_or_else(|| CliError("no xv11 profile".into()))?;
    let mut config = SimConfig::new(world, lidar, seed);
    let options = Options {
        controller: Some(setting.controller),
        gains: setting.gains,
        duration_s: Some(args.duration),
        ..Options::default()
    };
    let entry = scenario::find(&args.scenario)
        .ok_or_else(|| CliError(format!("unknown scenario {}", args.scenario)))?;
    let flight = entry
        .prepare(&options, &mut config)
        .map_err(|e| CliError(format!("--controller {}: {e}", setting.controller.name())))?;
    let mut samples = StateSamples::default();
    let report =
        scenario::fly(&config, flight, &mut samples).map_err(|e| CliError(format!("room: {e}")))?;
    let out = &report.outcome;
    let minutes = out.sim_seconds / 60.0;
    let e = &out.energy;
    let held = matches!(out.status, Status::Completed);
    let log = report.onboard.as_ref();
    // The window the hold error is scored on: from the end of the climb's transient.
    let hold_from_s = log
        .and_then(|l| l.modes.iter().find(|(_, m)| *m == FlightMode::Hold))
        .map_or(f64::INFINITY, |(t, _)| *t + SETTLE_S);
    let hold = &samples.0[samples.0.partition_point(|s| s.t_s < hold_from_s)..];
    let floor = out.still_hover.as_ref().ok_or_else(|| {
        CliError(format!(
            "seed {seed}: the vehicle has no balanced still hover to measure against"
        ))
    })?;
    let excess = hover_excess(&config.vehicle, floor, hold).unwrap_or(HoverExcess {
        floor_w: floor.power.total_w(),
        measured_w: f64::NAN,
        ..HoverExcess::default()
    });
    Ok(Run {
        error_m: report.score.hold.filter(|_| held).map(|h| h.rms_m),
        parts_wh_min: [e.motors_wh, e.escs_wh, e.avionics_wh].map(|x| x / minutes),
        hold_power_w: excess.floor_w + excess.measured_w,
        excess,
        jitter: log.and_then(|l| l.motor_jitter()).unwrap_or(f64::NAN),
    })
}

/// Runs every (setting, seed) flight on `threads` threads; results in setting-major order,
/// the same whatever the thread count.
fn fly_all(args: &EnergyArgs, settings: &[Setting], threads: usize) -> Result<Vec<Run>, CliError> {
    let seeds = args.seeds as usize;
    let jobs = settings.len() * seeds;
    let results: Vec<Mutex<Option<Result<Run, CliError>>>> =
        (0..jobs).map(|_| Mutex::new(None)).collect();
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..threads.min(jobs) {
            scope.spawn(|| loop {
                let job = next.fetch_add(1, Ordering::Relaxed);
                if job >= jobs {
                    break;
                }
                let seed = args.seed.wrapping_add((job % seeds) as u64);
                let run = fly(args, settings[job / seeds], seed);
                if let Ok(mut slot) = results[job].lock() {
                    *slot = Some(run);
                }
            });
        }
    });
    results
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err(CliError("a flight thread panicked".into())))
        })
        .collect()
}

fn mean(xs: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = xs.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    sum / n.max(1) as f64
}

fn aggregate(setting: Setting, runs: &[Run]) -> Row {
    let failed = runs.iter().filter(|r| r.error_m.is_none()).count();
    let error_m = if failed > 0 {
        f64::NAN
    } else {
        mean(runs.iter().filter_map(|r| r.error_m))
    };
    let parts_wh_min = [0, 1, 2].map(|i| mean(runs.iter().map(|r| r.parts_wh_min[i])));
    let hold_power_w = mean(runs.iter().map(|r| r.hold_power_w));
    Row {
        excess: HoverExcess::mean(runs.iter().map(|r| &r.excess)),
        setting,
        point: Point {
            error_m,
            // W over the hold phase -> Wh per minute.
            energy_wh_min: hold_power_w / 60.0,
        },
        parts_wh_min,
        hold_power_w,
        jitter: mean(runs.iter().map(|r| r.jitter)),
        failed,
    }
}

/// One controller's figures against its own default (`rows[0]`), and whether it meets the
/// question's target.
/// How well the second-order model (3/8 Var(T)/W², the tilt, the rotors' uneven split) predicts
/// the measured excess over the settings that held: the largest and the mean difference, W.
fn excess_check(rows: &[Row]) -> serde_json::Value {
    let held: Vec<&Row> = rows.iter().filter(|r| r.failed == 0).collect();
    let diff = |r: &&Row| r.excess.predicted_w - r.excess.measured_w;
    json!({
        "settings": held.len(),
        "largest_abs_predicted_minus_measured_w":
            held.iter().map(|r| diff(r).abs()).fold(0.0, f64::max),
        "mean_predicted_minus_measured_w": mean(held.iter().map(diff)),
        "measured_excess_range_w": [
            held.iter().map(|r| r.excess.measured_w).fold(f64::INFINITY, f64::min),
            held.iter().map(|r| r.excess.measured_w).fold(f64::NEG_INFINITY, f64::max),
        ],
    })
}

fn controller_summary(rows: &[Row]) -> (serde_json::Value, bool) {
    let points: Vec<Point> = rows.iter().map(|r| r.point).collect();
    let verdict = pareto::verdict(&points, 0, ERROR_SLACK, ENERGY_SAVING);
    let d = &rows[0];
    let total: f64 = d.parts_wh_min.iter().sum();
    let best = verdict.best_within_slack.map(|i| &rows[i]);
    // Any setting's hold power is at least the floor, so it saves at most the default's excess.
    let saving_bound = d.excess.measured_w / d.hold_power_w;
    let value = json!({
        "default_rms_hold_error_m": d.point.error_m,
        "default_hold_energy_wh_per_min": d.point.energy_wh_min,
        "default_hold_power_w": d.hold_power_w,
        "default_still_hover_w": d.excess.floor_w,
        "default_over_still_hover": d.excess.measured_fraction(),
        "default_excess_w": d.excess.measured_w,
        "default_excess_parts_w": d.excess.parts().iter()
            .map(|(name, w)| (name.to_string(), json!(w)))
            .collect::<serde_json::Map<_, _>>(),
        "largest_possible_saving": saving_bound,
        "bound": format!(
            "the default spends {:.2} % above the still-hover floor, so no tuning can save more \
             than {:.2} %",
            100.0 * d.excess.measured_fraction(),
            100.0 * saving_bound,
        ),
        "excess_check": excess_check(rows),
        "default_power_fraction": d.parts_wh_min.map(|p| p / total),
        "failed_settings": rows.iter().filter(|r| r.failed > 0).count(),
        "best_saving_within_10pct_error": verdict.saving_within_slack,
        "best_setting": best.map(|r| json!({
            "position_kp": r.setting.gains.position_kp,
            "velocity_kp": r.setting.gains.velocity_kp,
            "command_tau_s": r.setting.gains.command_tau_s,
            "rms_hold_error_m": r.point.error_m,
            "hold_energy_wh_per_min": r.point.energy_wh_min,
        })),
        "largest_saving_any_error": verdict.largest_saving,
        "target_met": verdict.met,
    });
    (value, verdict.met)
}

/// The still hover of the nominal airframe (identical rotors), W.
fn nominal_still_hover_w() -> Result<f64, CliError> {
    let v = VehicleParams::f450();
    let dynamics = Dynamics::new(&v, [1.0; 4], 1e-3);
    StillHover::of(&v, &dynamics)
        .map(|h| h.power.total_w())
        .ok_or_else(|| CliError("the nominal vehicle has no still hover".into()))
}

fn stage(dir: &Path, name: &str) -> Result<OutputFile, CliError> {
    Ok(OutputFile::stage(&dir.join(name))?)
}

pub fn run(args: EnergyArgs) -> CliResult {
    let settings = settings(&args);
    let threads = args
        .threads
        .map(|n| n as usize)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError(format!("--out {}: {e}", args.out.display())))?;
    let (pareto_png, power_png, excess_png) = (
        stage(&args.out, "pareto.png")?,
        stage(&args.out, "power.png")?,
        stage(&args.out, "excess.png")?,
    );
    let runs = fly_all(&args, &settings, threads)?;
    let rows: Vec<Row> = settings
        .iter()
        .zip(runs.chunks(args.seeds as usize))
        .map(|(s, r)| aggregate(*s, r))
        .collect();
    let points: Vec<Point> = rows.iter().map(|r| r.point).collect();
    let front = pareto::front(&points);
    // Every setting flies the same seeds, so the same bodies: one floor for all.
    let floor_w = rows[0].excess.floor_w;
    let nominal_w = nominal_still_hover_w()?;
    output::write(
        &args.out.join("energy.tsv"),
        energy_table::table(&rows, &front).as_bytes(),
    )?;
    write_png(pareto_png, |p| {
        energy_plot::pareto(p, &rows, &front, floor_w / 60.0)
    })?;
    let lowest = front
        .iter()
        .copied()
        .min_by(|&a, &b| points[a].energy_wh_min.total_cmp(&points[b].energy_wh_min))
        .map(|i| &rows[i]);
    write_png(power_png, |p| energy_plot::breakdown(p, &rows[0], lowest))?;
    write_png(excess_png, |p| {
        excess_plot::excess(p, &rows, ENERGY_SAVING * rows[0].hold_power_w)
    })?;
    // Each controller's settings are contiguous, its default first (see `settings`).
    let per_controller: Vec<(&str, serde_json::Value, bool)> = rows
        .chunk_by(|a, b| a.setting.controller == b.setting.controller)
        .map(|chunk| {
            let (value, met) = controller_summary(chunk);
            (chunk[0].setting.controller.name(), value, met)
        })
        .collect();
    let summary = json!({
        "settings": rows.len(),
        "seeds": args.seeds,
        "flights": runs.len(),
        "scenario": args.scenario,
        "duration_s": args.duration,
        "still_hover_power_w": floor_w,
        "still_hover_power_per_seed_w": runs[..args.seeds as usize]
            .iter()
            .map(|r| r.excess.floor_w)
            .collect::<Vec<_>>(),
        "nominal_still_hover_power_w": nominal_w,
        "still_hover_note": "the floor is each flown vehicle's still hover, its seed's rotor \
            thrust mismatch included (a rotor giving more thrust at a given speed carries its \
            share on less power), averaged over the seeds; the nominal figure is the airframe \
            with identical rotors",
        "pareto_settings": front.len(),
        "failed_settings": rows.iter().filter(|r| r.failed > 0).count(),
        "controllers": per_controller
            .iter()
            .map(|(name, v, _)| (name.to_string(), v.clone()))
            .collect::<serde_json::Map<_, _>>(),
        "target_met": per_controller.iter().any(|c| c.2),
    });
    let text = serde_json::to_string_pretty(&summary).map_err(|e| CliError(e.to_string()))?;
    output::write(&args.out.join("summary.json"), (text + "\n").as_bytes())?;
    print_summary(&summary, args.json);
    Ok(())
}
