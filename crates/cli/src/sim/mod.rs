//! `plumbline sim`: closed-loop flight in the simulator, writing the emulated sensor logs and the
//! ground truth in the benchmark formats (DESIGN.md §4, §5). The scenarios and their scoring are
//! `plumbline-sim`'s; this command parses, writes files, plots and prints.

mod explore;
mod ground;
mod mavlink;
mod model_error;
mod onboard;
mod outputs;
mod pace;
pub(crate) mod plot;
mod view;
mod world;

use crate::log_args::LogArgs;
use crate::numeric::{within, Range};
use crate::plot::write_png;
use crate::report::{print_summary, progress, CliError, CliResult};
use crate::view_args::{self, ViewArgs};
use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::Args;
use outputs::{create, Collector, SensorLogs};
use plumbline_io::input::read_text;
use plumbline_io::output::{self, check_distinct};
use plumbline_sim::disturb::Push;
use plumbline_sim::math::Vec3;
use plumbline_sim::runner::{SetupError, SimConfig, Status, PHYSICS_HZ_RANGE};
use plumbline_sim::scenario::{self, Report, ScenarioError};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::vehicle::VehicleParams;
use plumbline_sim::world::World;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct SimArgs {
    /// A shipped world (room, office, building, intel, hall), a world file (crates/sim/WORLDS.md)
    /// or an occupancy image (map.pgm with map.yaml beside it).
    #[arg(long, default_value = "office")]
    pub world: String,
    /// What to fly: `survey` is flown by the test pilot, the others by the onboard stack.
    #[arg(long, default_value = "survey", value_parser = scenario_names())]
    pub scenario: String,
    #[command(flatten)]
    pub closed_loop: onboard::ClosedLoopArgs,
    #[command(flatten)]
    pub model_error: model_error::ModelErrorArgs,
    #[arg(long, default_value = "xv11", value_parser = ["xv11", "urg04lx", "utm30lx"])]
    pub lidar: String,
    /// Vehicle preset (f450, pelican) or a TOML file (`base = "..."` plus overrides).
    #[arg(long, default_value = "f450")]
    pub vehicle: String,
    /// Run length of the closed-loop scenarios (default 60; `explore` 600, and it plans its way
    /// home to be down by then) and of the test pilot's `hold`;
    /// an upper bound on the flight for `survey`, s. Valid range: (0, 86400].
    #[arg(long, value_parser = within::<f64>(Range::above(0.0, 86400.0)))]
    pub duration: Option<f64>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Physics rate, Hz (fixed-step RK4). Valid range: [100, 20000].
    #[arg(long, default_value_t = 1000.0, value_parser = within::<f64>(
        Range::closed(*PHYSICS_HZ_RANGE.start(), *PHYSICS_HZ_RANGE.end())))]
    pub physics_hz: f64,
    /// Turn off turbulence.
    #[arg(long)]
    pub no_gusts: bool,
    /// Leave the world's walking people out.
    #[arg(long)]
    pub no_people: bool,
    /// A push on the frame: `START,DURATION,FX,FY,FZ` (s, s, N world frame); repeatable.
    #[arg(long, value_parser = parse_push)]
    pub push: Vec<Push>,
    /// Instead of flying: rasterise this CARMEN log's laser hits at its poses into a world
    /// (NAME.world, NAME.pgm, NAME.yaml in --out, NAME from the log's file name).
    #[arg(long, value_name = "LOG")]
    pub rasterize: Option<PathBuf>,
    #[command(flatten)]
    pub ground: ground::GroundArgs,
    #[command(flatten)]
    pub log_args: LogArgs,
    #[command(flatten)]
    pub view: ViewArgs,
    /// Write scans.clf, imu.csv, sonar.csv, truth.txt, truth.relations, summary.json and plots.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The catalogue's scenarios, each with its one line of help.
fn scenario_names() -> PossibleValuesParser {
    PossibleValuesParser::new(
        scenario::CATALOGUE
            .iter()
            .map(|e| PossibleValue::new(e.name).help(e.about)),
    )
}

fn parse_push(s: &str) -> Result<Push, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [start_s, duration_s, fx, fy, fz]
            if v.iter().all(|x| x.is_finite()) && start_s >= 0.0 && duration_s >= 0.0 =>
        {
            Ok(Push {
                start_s,
                duration_s,
                force_n: Vec3::new(fx, fy, fz),
            })
        }
        _ => Err(
            "expected START,DURATION,FX,FY,FZ (five finite numbers, start and duration >= 0)"
                .into(),
        ),
    }
}

pub fn load_world(arg: &str) -> Result<World, CliError> {
    if let Some(w) = World::shipped(arg) {
        return w.map_err(|e| CliError(format!("shipped world {arg}: {e}")));
    }
    if arg.ends_with(".pgm") {
        return world::load_pgm(Path::new(arg));
    }
    let text = read_text(Path::new(arg)).map_err(|e| {
        CliError(format!(
            "{e} (shipped worlds: room, office, building, intel, hall)"
        ))
    })?;
    World::parse(&text).map_err(|e| CliError(format!("{arg}: {e}")))
}

fn load_vehicle(arg: &str) -> Result<VehicleParams, CliError> {
    if let Some(v) = VehicleParams::preset(arg) {
        return Ok(v);
    }
    let text =
        read_text(Path::new(arg)).map_err(|e| CliError(format!("{e} (presets: f450, pelican)")))?;
    VehicleParams::from_toml(&text).map_err(|e| CliError(format!("{arg}: {e}")))
}

/// Every file a flight may write into `--out DIR`.
const OUTPUT_NAMES: &[&str] = &[
    "scans.clf",
    "imu.csv",
    "sonar.csv",
    "truth.txt",
    "truth.relations",
    "summary.json",
    "top.png",
    "flight.png",
    "position_error.png",
    "motors.png",
    "map.png",
    "explored.png",
];

/// Refuses a world or vehicle file that a flight's outputs would overwrite.
fn check_inputs_outside(args: &SimArgs, dir: &Path) -> CliResult {
    let inputs: Vec<(&str, &Path)> = [("--world", &args.world), ("--vehicle", &args.vehicle)]
        .into_iter()
        .map(|(role, arg)| (role, Path::new(arg.as_str())))
        .filter(|(_, p)| p.is_file())
        .collect();
    let paths: Vec<PathBuf> = OUTPUT_NAMES.iter().map(|n| dir.join(n)).collect();
    let outputs: Vec<(&str, &Path)> = paths.iter().map(|p| ("--out", p.as_path())).collect();
    Ok(check_distinct(&inputs, &outputs)?)
}

fn summary(args: &SimArgs, config: &SimConfig, report: &Report, wall_s: f64) -> serde_json::Value {
    let (out, score) = (&report.outcome, &report.score);
    let (status, status_time) = match &out.status {
        Status::Completed => ("completed".to_string(), None),
        Status::Crashed { t_s, reason } => (format!("crashed: {reason}"), Some(*t_s)),
        Status::Diverged { t_s } => ("diverged".to_string(), Some(*t_s)),
        Status::BatteryExhausted { t_s } => ("battery exhausted".to_string(), Some(*t_s)),
    };
    let [motors, escs, avionics] = out.energy.fractions();
    json!({
        "world": config.world.name,
        "scenario": args.scenario,
        "lidar": config.lidar.name,
        "vehicle": config.vehicle.name,
        "seed": config.seed,
        "physics_hz": config.physics_hz,
        "status": status,
        "status_time_s": status_time,
        "crashed": matches!(out.status, Status::Crashed { .. }),
        "sim_seconds": out.sim_seconds,
        "wall_seconds": wall_s,
        "realtime_factor": out.sim_seconds / wall_s.max(1e-9),
        "scans": out.scans,
        "distance_flown_m": out.distance_flown_m,
        "rms_hold_error_m": score.hold.map(|h| h.rms_m),
        "max_hold_error_m": score.hold.map(|h| h.max_m),
        "rms_track_error_m": score.track.map(|h| h.rms_m),
        "max_track_error_m": score.track.map(|h| h.max_m),
        "rms_track_control_error_m": score.track_parts.map(|p| p.control.rms_m),
        "rms_track_estimate_error_m": score.track_parts.map(|p| p.estimate.rms_m),
        "estimate_drift_m": score.estimate_drift_m,
        "min_clearance_m": out.min_clearance_m,
        "energy_wh": out.energy.total_wh(),
        "battery_energy_wh": out.battery_energy_wh,
        "power_fraction": { "motors": motors, "escs": escs, "avionics": avionics },
        "battery_end_v": out.battery_end_v,
        "battery_min_v": out.battery_min_v,
        "battery_end_soc": out.battery_end_soc,
        "battery_low_s": out.battery_low_at_s,
        "model_error": args.model_error.summary(config),
    })
}

/// `--rasterize LOG`: writes the world and reports its size.
fn rasterize(args: &SimArgs, log_path: &Path) -> CliResult {
    let dir = args
        .out
        .as_deref()
        .ok_or_else(|| CliError("--rasterize needs --out DIR".into()))?;
    let name = log_path
        .file_name()
        .map_or("log".into(), |s| s.to_string_lossy().into_owned());
    let name = name
        .split('.')
        .next()
        .unwrap_or("log")
        .trim_end_matches("-corrected")
        .to_string();
    let paths = ["world", "pgm", "yaml"].map(|ext| dir.join(format!("{name}.{ext}")));
    let outputs = paths.each_ref().map(|p| ("--out", p.as_path()));
    check_distinct(&[("--rasterize", log_path)], &outputs)?;
    let log = args.log_args.read(log_path)?;
    let (world, grid) = world::rasterize(&log, &log_path.display().to_string(), &name)?;
    world::write_world(dir, &world, &grid)?;
    let [x0, y0, x1, y1] = world.bounds();
    let summary = json!({
        "world": world.name,
        "scans": log.scans.len(),
        "walls": world.walls.len(),
        "waypoints": world.path.len(),
        "size_m": [x1 - x0, y1 - y0],
        "resolution_m": grid.resolution_m,
    });
    print_summary(&summary, args.json);
    Ok(())
}

/// A scenario refused, in the command's own terms.
fn scenario_error(args: &SimArgs, e: ScenarioError) -> CliError {
    match e {
        ScenarioError::Controller {
            scenario,
            controller,
            reason,
            instead,
        } => {
            let c = controller.name();
            let advice = match instead {
                Some(i) => format!("use --controller {}", i.name()),
                None => format!("drop --controller {c}"),
            };
            CliError(format!(
                "--scenario {scenario} --controller {c}: {reason}; {advice}"
            ))
        }
        ScenarioError::World(e) => CliError(format!("{}: {e}", args.world)),
        ScenarioError::Setup(e @ SetupError::World(_)) => CliError(format!("{}: {e}", args.world)),
        ScenarioError::Setup(e) => CliError(e.to_string()),
    }
}

pub fn run(args: SimArgs) -> CliResult {
    if let Some(log) = args.rasterize.as_deref() {
        return rasterize(&args, log);
    }
    let world = load_world(&args.world)?;
    let lidar = LidarProfile::by_name(&args.lidar)
        .ok_or_else(|| CliError(format!("unknown lidar {}", args.lidar)))?;
    let mut config = SimConfig::new(world, lidar, args.seed);
    config.vehicle = load_vehicle(&args.vehicle)?;
    config.physics_hz = args.physics_hz;
    config.pushes.clone_from(&args.push);
    config.people = !args.no_people;
    if args.no_gusts {
        config.gusts = None;
    }
    args.model_error.apply(&mut config);
    if let Some(d) = args.duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError(format!("--duration must be positive, got {d}")));
        }
    }
    let entry = scenario::find(&args.scenario)
        .ok_or_else(|| CliError(format!("unknown scenario {}", args.scenario)))?;
    let options = args.closed_loop.options(args.duration);
    let mut flight = entry
        .prepare(&options, &mut config)
        .map_err(|e| scenario_error(&args, e))?;
    if let Some(dir) = args.out.as_deref() {
        check_inputs_outside(&args, dir)?;
    }
    let view = args.view.start()?.map(Rc::new);
    if let Some(v) = &view {
        let station = view::ViewStation::new(v.clone(), &config.world);
        flight.link_ground(Box::new(station)).map_err(|_| {
            CliError(
                "--view needs a scenario flown by the onboard stack; the test pilot has no \
                 ground link (use --controller pid)"
                    .into(),
            )
        })?;
    }
    let linked = ground::link(&args.ground, &mut flight)?;
    // Every check has passed: from here on the run starts, so the files may be staged.
    let logs = args.out.as_deref().map(SensorLogs::create).transpose()?;
    let bar = progress(flight.planned_s.ceil() as u64, "sim");
    let mut collector = Collector {
        logs,
        states: Vec::new(),
        bar,
        error: None,
    };
    let started = Instant::now();
    let report = scenario::fly(&config, flight, &mut collector)
        .map_err(|e| CliError(format!("{}: {e}", args.world)))?;
    let wall_s = started.elapsed().as_secs_f64();
    collector.bar.finish_and_clear();
    if let Some(e) = collector.error.take() {
        return Err(CliError(format!("writing outputs: {e}")));
    }
    let mut summary = summary(&args, &config, &report, wall_s);
    if let Some(v) = &view {
        summary["view"] = view_args::summary(v);
    }
    if let (Some(log), Some(score)) = (&report.onboard, &report.score.onboard) {
        onboard::extend_summary(&mut summary, &args.closed_loop, &config, log, score);
        if let Some(dir) = args.out.as_deref() {
            onboard::plots(dir, &config, log, &collector.states)?;
        }
    }
    if let (Some(score), Some(exploration)) = (&report.score.explore, &report.exploration) {
        explore::extend_summary(&mut summary, score, exploration);
        if let Some(dir) = args.out.as_deref() {
            explore::plots(dir, &config, exploration, &collector.states)?;
        }
    }
    if let Some(stats) = &linked.mavlink {
        summary["mavlink"] = stats.borrow().summary();
    }
    if let (Some(dir), Some(logs)) = (args.out.as_deref(), collector.logs.take()) {
        let poses = logs.finish(dir)?;
        let states = &collector.states;
        write_png(create(dir, "top.png")?, |p| {
            plot::top_view(p, &config.world, states, &poses)
        })?;
        write_png(create(dir, "flight.png")?, |p| plot::time_series(p, states))?;
        let text = serde_json::to_string_pretty(&summary).map_err(|e| CliError(e.to_string()))?;
        output::write(&dir.join("summary.json"), (text + "\n").as_bytes())?;
    }
    print_summary(&summary, args.json);
    Ok(())
}
