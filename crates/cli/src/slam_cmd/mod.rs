//! `plumbline slam LOG`: lidar SLAM over a log (DESIGN.md §4): a pose for every scan, the map
//! as map_server files and a picture, the pose graph as g2o text, and, for a simulated log
//! given its world, how far the map's walls lie from the true ones.

mod outputs;
mod truth;

use crate::log_args::{no_scans, odometry_prior, report_bad_lines, LogArgs};
use crate::odometry_cmd::{percentile, MAX_BEAMS};
use crate::plot::PlotScans;
use crate::report::{print_summary, progress_bytes, CliError, CliResult};
use clap::Args;
use plumbline_core::matching::PriorFusion;
use plumbline_core::scan::Scan;
use plumbline_io::carmen::{open_log, OdomPose};
use plumbline_io::output::check_distinct;
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_slam::map_files::check_writable;
use plumbline_slam::{local_map_cells, Slam, SlamConfig};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args, Debug)]
pub struct SlamArgs {
    /// CARMEN log (FLASER or ROBOTLASER1 lines; .gz is fine).
    pub log: PathBuf,
    /// Use the log's odometry as the motion guess (default: lidar only).
    #[arg(long)]
    pub odom_prior: bool,
    /// How far the log's odometry strays over one scan interval, one standard deviation:
    /// FLOOR_M,PER_M,FLOOR_RAD,PER_RAD (a floor plus a share of the distance, and of the turn).
    /// Given, each match is combined with the odometry by their covariances, so the odometry
    /// decides where the lidar sees nothing (along a bare corridor) and the lidar where it
    /// sees well. Without it the odometry is only each match's starting guess.
    #[arg(
        long,
        requires = "odom_prior",
        value_name = "FLOOR_M,PER_M,FLOOR_RAD,PER_RAD"
    )]
    pub odom_noise: Option<String>,
    /// Write the trajectory (`timestamp x y theta`, one line per scan) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the map as PREFIX.pgm + PREFIX.yaml (ROS map_server), PREFIX.png (a picture with
    /// the path) and the pose graph as PREFIX.g2o.
    #[arg(long, value_name = "PREFIX")]
    pub map: Option<PathBuf>,
    /// Draw the points of evenly spaced scans at their final poses, with the path, into this
    /// PNG (a `.png` file).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// The simulated world the log was flown in (a shipped name or a world file): score the
    /// map against its walls (`map_error_m`). Needs --truth.
    #[arg(long, requires = "truth")]
    pub world: Option<String>,
    /// The simulator's truth.txt for the log: where the map frame (the first scan's pose) lies
    /// in the world.
    #[arg(long, requires = "world")]
    pub truth: Option<PathBuf>,
    /// The lidar that took the log, if it spins slowly against the motion (xv11, urg04lx,
    /// utm30lx): each beam is given its time within the revolution, and the motion during the
    /// revolution is removed before matching. Leave out for logs whose lidar's sweep is short
    /// against the motion (the SICK scanners of the benchmark logs).
    #[arg(long, value_name = "NAME")]
    pub lidar: Option<String>,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Conditioning below which matches of a named lidar's scans have their weakest direction
/// checked for surfaces that face it (`MatchConfig::localizability_check_below`). On the
/// simulated XV-11 office surveys, seeds 1-10: mean map error 0.141 -> 0.103 m, worst 0.378 ->
/// 0.150 m.
const LOCALIZABILITY_CHECK_BELOW: f32 = 0.25;

pub fn run(args: SlamArgs) -> CliResult {
    let wall = Instant::now();
    // Every output is checked before the work starts: a typo in a prefix should not cost the
    // whole log.
    let map_paths = args.map.as_deref().map(check_writable).transpose()?;
    let g2o = args.map.as_deref().map(outputs::g2o_path);
    let mut outputs: Vec<(&str, &Path)> = [("--out", &args.out), ("--plot", &args.plot)]
        .into_iter()
        .filter_map(|(role, p)| p.as_deref().map(|p| (role, p)))
        .collect();
    if let (Some(m), Some(g)) = (&map_paths, &g2o) {
        outputs.extend([&m.pgm, &m.yaml, &m.png, g].map(|p| ("--map", p.as_path())));
    }
    let world_file = args.world.as_deref().map(Path::new).filter(|p| p.is_file());
    let inputs: Vec<(&str, &Path)> = [
        ("LOG", Some(args.log.as_path())),
        ("--truth", args.truth.as_deref()),
        ("--world", world_file),
    ]
    .into_iter()
    .filter_map(|(role, p)| p.map(|p| (role, p)))
    .collect();
    check_distinct(&inputs, &outputs)?;
    let staged = outputs::Staged::new(
        args.out.as_deref(),
        args.plot.as_deref(),
        args.map.as_deref(),
    )?;
    let truth = args
        .world
        .as_deref()
        .zip(args.truth.as_deref())
        .map(|(w, t)| truth::Truth::load(w, t))
        .transpose()?;
    let beam_dt_s = args
        .lidar
        .as_deref()
        .map(|name| {
            LidarProfile::by_name(name)
                .map(|p| p.beam_dt_s() as f32)
                .ok_or_else(|| {
                    CliError(format!(
                        "--lidar {name}: unknown lidar; use xv11, urg04lx or utm30lx"
                    ))
                })
        })
        .transpose()?;
    let (mut reader, read_progress) = open_log(&args.log, &args.log_args.options())?;
    let mut config = SlamConfig {
        deskew: beam_dt_s.is_some(),
        ..SlamConfig::default()
    };
    if beam_dt_s.is_some() {
        // A lidar named on the command line is one of the slow, noisy or short-range ones
        // whose line normals tilt enough to fake information along a corridor's axis; the
        // benchmark logs' SICK scanners measure small-angle structure for real and do better
        // without the check (Intel 0.018 -> 0.025 m with it).
        config.odometry.matcher.localizability_check_below = LOCALIZABILITY_CHECK_BELOW;
    }
    config.odometry.prior_fusion = args.odom_noise.as_deref().map(odometry_noise).transpose()?;
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<MAX_BEAMS> =
        Slam::new(config, &mut cells, true).map_err(|e| CliError(e.0))?;
    let bar = progress_bytes(read_progress.total, "slam");
    let mut anchors: Vec<outputs::Anchor> = Vec::new();
    let mut plot_scans = args.plot.is_some().then(PlotScans::new);
    let mut times_us = Vec::new();
    let mut scan: Box<Scan<MAX_BEAMS>> = Box::default();
    let mut previous_odom: Option<OdomPose> = None;
    let mut lost_s = 0.0;
    let mut span_s: Option<(f64, f64)> = None;
    let mut seen = outputs::SeenThrough::new();
    let map_wanted = args.map.is_some() || truth.is_some();
    while let Some(rec) = reader.next_scan()? {
        *scan = rec.to_scan().map_err(|_| {
            CliError(format!(
                "{}: scan {} has {} beams; at most {MAX_BEAMS} are supported",
                args.log.display(),
                anchors.len() + 1,
                rec.beam_count()
            ))
        })?;
        if let Some(dt) = beam_dt_s {
            time_beams(&mut scan, dt);
        }
        let prior = odometry_prior(args.odom_prior, previous_odom, rec.odom);
        previous_odom = rec.odom;
        let start = Instant::now();
        let out = slam.add_scan(&scan, prior);
        times_us.push(start.elapsed().as_secs_f64() * 1e6);
        // The time since the last scan counts as lost when this scan could not be matched.
        if let (true, Some((_, last))) = (out.predicted, span_s) {
            lost_s += (rec.timestamp_s - last).abs();
        }
        span_s = Some((span_s.map_or(rec.timestamp_s, |s| s.0), rec.timestamp_s));
        if map_wanted {
            seen.add(slam.matched_scan(&scan));
        }
        if let Some(p) = plot_scans.as_mut() {
            p.add(&rec);
        }
        anchors.push(outputs::Anchor {
            timestamp_text: rec.timestamp_text,
            timestamp_s: rec.timestamp_s,
            keyframe: out.keyframe,
            relative: out.relative,
            lost: out.predicted,
        });
        bar.set_position(read_progress.bytes_read());
    }
    bar.finish_and_clear();
    report_bad_lines(reader.stats());
    let Some((first_s, last_s)) = span_s else {
        return Err(no_scans(&args.log));
    };
    let tracking = slam.tracking_stats();
    let finished = slam
        .finish()
        .ok_or_else(|| CliError("the SLAM back end stopped unexpectedly".into()))?;
    let backend = &finished.backend;
    let trajectory = outputs::trajectory(anchors, backend.poses());
    let written = staged.write(args.map.as_deref(), plot_scans, &trajectory, &seen, backend)?;
    let map_error = match (&truth, &written.grid) {
        (Some(truth), Some(grid)) => truth.map_error(grid, first_s)?,
        (Some(truth), None) => {
            truth.map_error(&outputs::grid(backend, &trajectory, &seen)?, first_s)?
        }
        _ => None,
    };
    times_us.sort_by(f64::total_cmp);
    let stats = backend.stats();
    let duration = last_s - first_s;
    let wall_s = wall.elapsed().as_secs_f64();
    let summary = json!({
        "scans": tracking.scans,
        "keyframes": stats.keyframes,
        "submaps": stats.keyframes.div_ceil(config.keyframes_per_submap.max(1)),
        "loop_candidates": stats.loop_candidates,
        "loop_closures_accepted": stats.loops_accepted,
        "loop_closures_rejected": stats.loops_rejected,
        "loop_closures_downweighted": stats.loops_downweighted,
        "optimisations": stats.optimisations,
        "keyframes_thinned": stats.thinned,
        "relocalizations": tracking.guess_searches_used,
        "relocalizations_failed": tracking.guess_searches_failed,
        "relocalizations_unconfirmed": tracking.guess_searches_unconfirmed,
        "predicted_scans": tracking.predicted_scans,
        "lost_intervals": tracking.lost_intervals,
        "lost_s": lost_s,
        "wall_s": wall_s,
        "realtime_factor": if wall_s > 0.0 { duration / wall_s } else { 0.0 },
        "median_scan_us": percentile(&times_us, 0.5),
        "p99_scan_us": percentile(&times_us, 0.99),
        "peak_rss_mb": peak_rss_mb(),
        "map_error_m": map_error.as_ref().map(|e| e.mean_m),
        "map_error_far_fraction": map_error.as_ref().map(|e| e.far_fraction),
        "map_occupied_cells": written.grid.as_ref().map(|g| g.occupied_cells().count()),
    });
    print_summary(&summary, args.json);
    Ok(())
}

/// The fusion of `--odom-noise FLOOR_M,PER_M,FLOOR_RAD,PER_RAD`: floors above zero (a prior
/// that claims to be exact cannot be combined), shares at least zero, all finite.
fn odometry_noise(text: &str) -> Result<PriorFusion, CliError> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| CliError(format!("--odom-noise {text}: {e}; give four numbers")))?;
    let [floor_m, per_m, floor_rad, per_rad] = values[..] else {
        return Err(CliError(format!(
            "--odom-noise {text}: expected FLOOR_M,PER_M,FLOOR_RAD,PER_RAD, found {} values",
            values.len()
        )));
    };
    for (name, v, least) in [
        ("FLOOR_M", floor_m, f32::MIN_POSITIVE),
        ("PER_M", per_m, 0.0),
        ("FLOOR_RAD", floor_rad, f32::MIN_POSITIVE),
        ("PER_RAD", per_rad, 0.0),
    ] {
        if !(v.is_finite() && v >= least) {
            let bound = if least > 0.0 { "above 0" } else { "0 or more" };
            return Err(CliError(format!(
                "--odom-noise: {name} is {v}; give a finite value {bound}"
            )));
        }
    }
    Ok(PriorFusion::new(floor_m, per_m, floor_rad, per_rad))
}

/// Gives beam k of `scan` the time `k * beam_dt_s` after the first (a log does not store it).
fn time_beams(scan: &mut Scan<MAX_BEAMS>, beam_dt_s: f32) {
    let untimed = scan.clone();
    scan.clear(untimed.stamp_s);
    for (k, beam) in untimed.beams().iter().enumerate() {
        let mut b = *beam;
        b.time_offset_s = beam_dt_s * k as f32;
        // As many beams as the scan held before: this cannot fail.
        let _ = scan.push(b);
    }
}

/// The process's peak resident memory, MB, from Linux's `/proc/self/status` (`None` elsewhere).
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
