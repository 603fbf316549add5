//! `plumbline slam LOG`: lidar SLAM over a log (DESIGN.md §4): a pose for every scan, the pose
//! graph, the map.

use crate::log_args::LogArgs;
use crate::odometry_cmd::{write_file, MAX_BEAMS};
use crate::report::{print_summary, progress, CliError, CliResult};
use clap::Args;
use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_io::carmen::OdomPose;
use plumbline_io::trajectory::{write_trajectory, TrajectoryPoint};
use plumbline_slam::{local_map_cells, Slam, SlamConfig};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct SlamArgs {
    /// CARMEN log (FLASER or ROBOTLASER1 lines; .gz is fine).
    pub log: PathBuf,
    /// Use the log's odometry as the motion guess (default: lidar only).
    #[arg(long)]
    pub odom_prior: bool,
    /// Write the trajectory (`timestamp x y theta`, one line per scan) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: SlamArgs) -> CliResult {
    let wall = Instant::now();
    let log = args.log_args.read(&args.log)?;
    let mut config = SlamConfig::default();
    if std::env::var("PL_NOLOOP").is_ok() {
        config.loops.max_candidates = 0;
    }
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<MAX_BEAMS> =
        Slam::new(config, &mut cells, true).map_err(|e| CliError(e.0))?;
    let bar = progress(log.scans.len() as u64, "slam");
    let mut anchors: Vec<(Option<usize>, Pose2)> = Vec::with_capacity(log.scans.len());
    let mut times_us = Vec::with_capacity(log.scans.len());
    let mut scan: Box<Scan<MAX_BEAMS>> = Box::default();
    let mut previous_odom: Option<OdomPose> = None;
    let mut lost_s = 0.0;
    let mut previous_stamp: Option<f64> = None;
    for (i, rec) in log.scans.iter().enumerate() {
        *scan = rec.to_scan().map_err(|_| {
            CliError(format!(
                "{}: scan {} has {} beams; at most {MAX_BEAMS} are supported",
                args.log.display(),
                i + 1,
                rec.beam_count()
            ))
        })?;
        let prior = match (args.odom_prior, previous_odom, rec.odom) {
            (true, Some(a), Some(b)) => Some(a.between(b).to_f32()),
            _ => None,
        };
        previous_odom = rec.odom;
        let start = Instant::now();
        let out = slam.add_scan(&scan, prior);
        times_us.push(start.elapsed().as_secs_f64() * 1e6);
        anchors.push((out.keyframe, out.relative));
        // Time since the last scan counts as lost when this scan could not be matched.
        if out.predicted {
            lost_s += previous_stamp.map_or(0.0, |p| (rec.timestamp_s - p).abs());
        }
        previous_stamp = Some(rec.timestamp_s);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let tracking = slam.tracking_stats();
    let finished = slam
        .finish()
        .ok_or_else(|| CliError("the SLAM back end stopped unexpectedly".into()))?;
    let poses = finished.backend.poses();
    if let Ok(path) = std::env::var("PL_DUMP_LOOPS") {
        let kfs = finished.backend.keyframes();
        let mut text = String::new();
        for e in finished
            .backend
            .graph()
            .edges()
            .iter()
            .filter(|e| e.kind == plumbline_slam::graph::EdgeKind::Loop)
        {
            text += &format!(
                "{:.6} {:.6} {} {} {}\n",
                kfs[e.from.index()].stamp_s,
                kfs[e.to.index()].stamp_s,
                e.measurement.x,
                e.measurement.y,
                e.measurement.theta
            );
        }
        std::fs::write(path, text).ok();
    }
    let trajectory: Vec<TrajectoryPoint> = log
        .scans
        .iter()
        .zip(&anchors)
        .map(|(rec, &(kf, rel))| TrajectoryPoint {
            timestamp_text: rec.timestamp_text.clone(),
            timestamp_s: rec.timestamp_s,
            pose: OdomPose::from_f32(kf.map_or(rel, |k| poses[k].compose(rel))),
        })
        .collect();
    if let Some(path) = &args.out {
        write_file(path, |w| write_trajectory(w, &trajectory))?;
    }
    times_us.sort_by(f64::total_cmp);
    let stats = finished.backend.stats();
    let duration = log.scans.last().map_or(0.0, |l| l.timestamp_s)
        - log.scans.first().map_or(0.0, |f| f.timestamp_s);
    let wall_s = wall.elapsed().as_secs_f64();
    let summary = json!({
        "scans": tracking.scans,
        "keyframes": stats.keyframes,
        "loop_candidates": stats.loop_candidates,
        "loop_closures_accepted": stats.loops_accepted,
        "loop_closures_rejected": stats.loops_rejected,
        "optimisations": stats.optimisations,
        "keyframes_thinned": stats.thinned,
        "loop_closures_downweighted": stats.loops_downweighted,
        "beams_held": stats.beams_held,
        "loop_rejections": stats.rejections,
        "relocalizations": tracking.guess_searches_used,
        "relocalizations_failed": tracking.guess_searches_failed,
        "predicted_scans": tracking.predicted_scans,
        "lost_s": lost_s,
        "wall_s": wall_s,
        "realtime_factor": duration / wall_s,
        "median_scan_us": percentile(&times_us, 0.5),
        "p99_scan_us": percentile(&times_us, 0.99),
        "peak_rss_mb": peak_rss_mb(),
    });
    print_summary(&summary, args.json);
    Ok(())
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let k = ((sorted.len() as f64 * p).ceil() as usize).clamp(1, sorted.len()) - 1;
    (sorted[k] * 100.0).round() / 100.0
}

/// The process's peak resident memory, MB, from Linux's `/proc/self/status` (`None` elsewhere).
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
