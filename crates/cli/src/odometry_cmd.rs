//! `plumbline odometry LOG`: lidar-only scan-to-scan odometry over a log (DESIGN.md §4).
//!
//! The log is read a scan at a time and each pose written as it is computed, so memory stays
//! flat however long the log, and a run that is stopped keeps the trajectory so far.

use crate::log_args::{no_scans, odometry_prior, report_bad_lines, LogArgs};
use crate::numeric::{within, Range};
use crate::plot::{plot_trajectory, stage_png, write_png, TrajectoryPlot};
use crate::report::{print_summary, progress_bytes, CliError, CliResult};
use clap::Args;
use plumbline_core::geom::Pose2;
use plumbline_core::matching::local_map::{
    LineMap, LineMapConfig, MapCell, MapUse, MappedOdometry, RefineConfig, RefineRefusal,
    RelocalizeConfig,
};
use plumbline_core::matching::{
    LidarOdometry, MatchConfig, MatchError, MatcherKind, MotionLimits, OdometryConfig, OdometryStep,
};
use plumbline_core::scan::Scan;
use plumbline_io::carmen::{open_log, OdomPose};
use plumbline_io::output::{check_distinct, OutputFile};
use plumbline_io::trajectory::{TrajectoryPoint, TrajectoryWriter};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Largest scan the command takes (a UTM-30LX has 1081 beams).
pub const MAX_BEAMS: usize = 2048;

#[derive(Args, Debug)]
pub struct OdometryArgs {
    /// CARMEN log (FLASER or ROBOTLASER1 lines; .gz is fine).
    pub log: PathBuf,
    /// Scan matcher.
    #[arg(long, default_value = "icl", value_parser = ["icl", "icl-paper", "icp", "plicp"])]
    pub matcher: String,
    /// With `--matcher icl-paper`: seed 000 sec. 4.2's rejection as written (a point whose cost
    /// exceeds four times the previous revolution's squared displacement is left out).
    #[arg(long)]
    pub paper_rejection: bool,
    /// Use the log's odometry as the initial guess (default: lidar only, constant velocity).
    #[arg(long)]
    pub odom_prior: bool,
    /// Write the trajectory (`timestamp x y theta`) here, a line per scan as it is computed.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Draw the trajectory over the scan points into this PNG (a `.png` file).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// New keyframe after this much travel, m. Valid range: (0, 10].
    #[arg(long, default_value_t = OdometryConfig::default().keyframe_distance_m,
          value_parser = within::<f32>(Range::above(0.0, 10.0)))]
    pub keyframe_distance: f32,
    /// New keyframe after this much turning, degrees. Valid range: (0, 180].
    #[arg(long, default_value_t = OdometryConfig::default().keyframe_angle_rad.to_degrees(),
          value_parser = within::<f32>(Range::above(0.0, 180.0)))]
    pub keyframe_angle_deg: f32,
    /// Do not align keyframes with the local map of the walls seen so far: plain
    /// scan-to-keyframe odometry, which drifts more (BENCHMARKS.md).
    #[arg(long)]
    pub no_local_map: bool,
    /// Do not search for the pose at which a keyframe lines up with walls mapped long ago
    /// (what takes the drift out at the end of a loop).
    #[arg(long)]
    pub no_relocalize: bool,
    /// Local map cell edge, m. Valid range: [0.01, 10].
    #[arg(long, default_value_t = LineMapConfig::default().cell_m,
          value_parser = within::<f32>(Range::closed(0.01, 10.0)))]
    pub map_cell: f32,
    /// Local map width, m (rounded to whole cells; the map rolls along with the vehicle).
    /// Valid range: (0, 10000], and at most 2048 cells a side.
    #[arg(long, default_value_t = 64.0, value_parser = within::<f32>(Range::above(0.0, 10000.0)))]
    pub map_size: f32,
    /// Weight of the scan match against the map when aligning a keyframe. Valid range: [0, 100].
    #[arg(long, default_value_t = RefineConfig::default().matcher_weight,
          value_parser = within::<f32>(Range::closed(0.0, 100.0)))]
    pub map_matcher_weight: f32,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: OdometryArgs) -> CliResult {
    let kind = MatcherKind::from_name(&args.matcher)
        .ok_or_else(|| CliError(format!("unknown matcher {}", args.matcher)))?;
    if args.paper_rejection && kind != MatcherKind::IclPaper {
        return Err(CliError(format!(
            "--paper-rejection applies to --matcher icl-paper, not {}; `icl` rejects on its own",
            args.matcher
        )));
    }
    // Everything that can be checked without the work comes first: options, names, outputs.
    let outputs: Vec<(&str, &Path)> = [("--out", &args.out), ("--plot", &args.plot)]
        .into_iter()
        .filter_map(|(role, p)| p.as_deref().map(|p| (role, p)))
        .collect();
    check_distinct(&[("LOG", &args.log)], &outputs)?;
    let read_options = args.log_args.options();
    let config = OdometryConfig {
        matcher: MatchConfig {
            paper_rejection: args.paper_rejection,
            ..MatchConfig::with_kind(kind)
        },
        keyframe_distance_m: args.keyframe_distance,
        keyframe_angle_rad: args.keyframe_angle_deg.to_radians(),
        motion_limits: Some(MotionLimits::default()),
        ..OdometryConfig::default()
    };
    let map_config = LineMapConfig {
        cell_m: args.map_cell,
        ..LineMapConfig::default()
    };
    let refine = RefineConfig {
        matcher_weight: args.map_matcher_weight,
        ..RefineConfig::default()
    };
    let use_map = !args.no_local_map;
    let side = if use_map {
        map_side(args.map_size, args.map_cell)?
    } else {
        0
    };
    let (mut reader, read_progress) = open_log(&args.log, &read_options)?;
    let mut traj_out = args
        .out
        .as_deref()
        .map(|p| OutputFile::stage(p).map(TrajectoryWriter::new))
        .transpose()?;
    let plot_out = args
        .plot
        .as_deref()
        .map(|p| stage_png("--plot", p))
        .transpose()?;
    let mut cells = vec![MapCell::default(); side * side];
    let mut odometry = if use_map {
        let map = LineMap::new(&mut cells, map_config)
            .map_err(|e| CliError(format!("local map: {e:?}")))?;
        let relocalize = (!args.no_relocalize).then(RelocalizeConfig::default);
        Odometer::Mapped(Box::new(MappedOdometry::new(
            config, map, refine, relocalize,
        )))
    } else {
        Odometer::Plain(Box::new(LidarOdometry::new(config)))
    };
    let (mut map_refined, mut map_refused, mut map_relocalized) = (0usize, 0usize, 0usize);
    let mut map_implausible = 0usize;
    let bar = progress_bytes(read_progress.total, "odometry");
    let mut plot = plot_out.as_ref().map(|_| TrajectoryPlot::new());
    let mut times_us = Vec::new();
    let (mut failed, mut keyframes, mut degenerate, mut rejected) = (0usize, 0usize, 0usize, 0u64);
    // Failed matches that converged somewhere the motion cannot have reached.
    let mut implausible = 0usize;
    let (mut recovered, mut iterations) = (0usize, 0u64);
    let mut first_failure: Option<String> = None;
    let mut scan: Box<Scan<MAX_BEAMS>> = Box::default();
    let mut previous_odom: Option<OdomPose> = None;
    let mut lost = LostTally::default();
    let mut scans = 0usize;
    loop {
        let rec = match reader.next_scan() {
            Ok(Some(rec)) => rec,
            Ok(None) => break,
            Err(e) => return Err(kept_so_far(e.into(), traj_out.take(), scans)),
        };
        scans += 1;
        *scan = rec.to_scan().map_err(|_| {
            let e = CliError(format!(
                "{}: scan {scans} has {} beams; at most {MAX_BEAMS} are supported",
                args.log.display(),
                rec.beam_count()
            ));
            kept_so_far(e, traj_out.take(), scans - 1)
        })?;
        let prior = odometry_prior(args.odom_prior, previous_odom, rec.odom);
        previous_odom = rec.odom;
        let start = Instant::now();
        let (step, map_use) = odometry.update(&scan, prior);
        let elapsed = start.elapsed();
        match map_use {
            Some(MapUse::Refined(_)) => map_refined += 1,
            Some(MapUse::Relocalized(_)) => map_relocalized += 1,
            Some(MapUse::Refused(refusal)) => {
                map_refused += 1;
                map_implausible += matches!(refusal, RefineRefusal::Implausible { .. }) as usize;
            }
            _ => {}
        }
        match step {
            OdometryStep::Started => keyframes += 1,
            OdometryStep::Matched {
                result,
                new_keyframe,
            } => {
                times_us.push(elapsed.as_secs_f64() * 1e6);
                keyframes += new_keyframe as usize;
                degenerate += result.quality.degenerate_direction.is_some() as usize;
                rejected += result.quality.rejected_dynamic as u64;
                recovered += result.quality.recovered as usize;
                iterations += result.quality.iterations as u64;
            }
            OdometryStep::Predicted { error, .. } => {
                failed += 1;
                implausible += usize::from(matches!(error, MatchError::Implausible { .. }));
                first_failure.get_or_insert_with(|| {
                    format!("scan {scans} at {}: {error}", rec.timestamp_text)
                });
            }
        }
        let predicted = matches!(step, OdometryStep::Predicted { .. });
        lost.note(rec.timestamp_s, predicted);
        let pose = OdomPose::from_f32(odometry.pose());
        if let Some(w) = traj_out.as_mut() {
            let point = TrajectoryPoint {
                timestamp_text: rec.timestamp_text.clone(),
                timestamp_s: rec.timestamp_s,
                pose,
                lost: predicted,
            };
            write_pose(w, &point)?;
        }
        if let Some(p) = plot.as_mut() {
            p.add(&rec, pose);
        }
        bar.set_position(read_progress.bytes_read());
    }
    bar.finish_and_clear();
    report_bad_lines(reader.stats());
    if scans == 0 {
        return Err(no_scans(&args.log));
    }
    if let Some(f) = &first_failure {
        eprintln!(
            "plumbline: {failed} match(es) failed and were bridged by prediction; first: {f}"
        );
    }
    if lost.scans > 0 {
        eprintln!(
            "plumbline: no measurement for {:.2} s in {} interval(s) ({} scans): their poses are a decaying \
             prediction, marked by `# lost` lines in the trajectory and not scored by `eval`",
            lost.seconds, lost.intervals, lost.scans
        );
    }
    if let Some(w) = traj_out {
        finish_trajectory(w)?.commit()?;
    }
    if let (Some(out), Some(data)) = (plot_out, &plot) {
        write_png(out, |p| plot_trajectory(p, data))?;
    }
    times_us.sort_by(f64::total_cmp);
    let stats = reader.stats();
    let summary = json!({
        "scans": scans,
        "matcher": kind.name(),
        "median_match_us": percentile(&times_us, 0.5),
        "p99_match_us": percentile(&times_us, 0.99),
        "failed_matches": failed,
        "implausible_matches": implausible,
        "lost_scans": lost.scans,
        "lost_intervals": lost.intervals,
        "lost_s": lost.seconds,
        "keyframes": keyframes,
        "degenerate_matches": degenerate,
        "rejected_points": rejected,
        "recovered_matches": recovered,
        "mean_iterations": if times_us.is_empty() { 0.0 } else { iterations as f64 / times_us.len() as f64 },
        "odom_prior": args.odom_prior,
        "local_map": use_map,
        "map_aligned_keyframes": map_refined,
        "map_refused_keyframes": map_refused,
        "map_implausible_keyframes": map_implausible,
        "map_relocalized_keyframes": map_relocalized,
        "non_monotonic_scans": stats.non_monotonic_scans,
        "bad_lines": stats.bad_lines,
    });
    print_summary(&summary, args.json);
    Ok(())
}

/// Writes one trajectory line and flushes it, so a run that is killed keeps every pose it
/// computed; the first line replaces the old file.
fn write_pose(w: &mut TrajectoryWriter<OutputFile>, point: &TrajectoryPoint) -> CliResult {
    w.push(point)
        .and_then(|()| w.get_mut().flush())
        .map_err(|e| w.get_ref().error(e))?;
    let out = w.get_mut();
    if !out.is_published() {
        out.publish()?;
    }
    Ok(())
}

/// Closes an open run of lost poses with its `# lost` line and hands back the file.
fn finish_trajectory(w: TrajectoryWriter<OutputFile>) -> Result<OutputFile, CliError> {
    let shown = w.get_ref().shown().to_string();
    w.finish().map_err(|e| CliError(format!("{shown}: {e}")))
}

/// An error part way through a log, saying where the poses computed before it are (with the
/// last run of lost poses marked as such).
fn kept_so_far(e: CliError, out: Option<TrajectoryWriter<OutputFile>>, scans: usize) -> CliError {
    match out {
        Some(w) if w.get_ref().is_published() => {
            let shown = w.get_ref().shown().to_string();
            let kept =
                finish_trajectory(w).and_then(|mut f| Ok(f.flush().map_err(|e| f.error(e))?));
            match kept {
                Ok(()) => CliError(format!(
                    "{e} (the trajectory of the {scans} scan(s) before it is in {shown})"
                )),
                Err(k) => CliError(format!("{e} (and the trajectory so far: {k})")),
            }
        }
        _ => e,
    }
}

/// Cells per side of the local map: each option is in its range already (checked while parsing),
/// but together they can still ask for more memory than any map needs.
fn map_side(size_m: f32, cell_m: f32) -> Result<usize, CliError> {
    /// 4 million cells, about 200 MB: past this a typo is likelier than a wish.
    const MAX_SIDE: f32 = 2048.0;
    let side = (size_m / cell_m).ceil();
    if side > MAX_SIDE {
        return Err(CliError(format!(
            "--map-size {size_m}: at most {MAX_SIDE} cells of {cell_m} m a side (a smaller map or larger --map-cell)"
        )));
    }
    Ok(side as usize)
}

/// How long the odometry went without a measurement: the time from the last measured scan to
/// the last scan of each run of predicted ones.
#[derive(Default)]
struct LostTally {
    scans: usize,
    intervals: usize,
    seconds: f64,
    previous: Option<(f64, bool)>,
}

impl LostTally {
    fn note(&mut self, stamp_s: f64, predicted: bool) {
        if predicted {
            self.scans += 1;
            let (was_lost, dt) = match self.previous {
                Some((t, was_lost)) => (was_lost, stamp_s - t),
                None => (false, 0.0),
            };
            self.intervals += !was_lost as usize;
            // Stamps that go backwards are counted and reported by the reader; they add nothing.
            self.seconds += dt.max(0.0);
        }
        self.previous = Some((stamp_s, predicted));
    }
}

/// Scan-to-keyframe odometry, with or without the local map.
enum Odometer<'m> {
    Plain(Box<LidarOdometry<MAX_BEAMS>>),
    Mapped(Box<MappedOdometry<'m, MAX_BEAMS>>),
}

impl Odometer<'_> {
    fn update(
        &mut self,
        scan: &Scan<MAX_BEAMS>,
        prior: Option<Pose2>,
    ) -> (OdometryStep, Option<MapUse>) {
        match self {
            Odometer::Plain(o) => (o.update(scan, prior), None),
            Odometer::Mapped(o) => {
                let s = o.update(scan, prior);
                (s.step, Some(s.map))
            }
        }
    }

    fn pose(&self) -> Pose2 {
        match self {
            Odometer::Plain(o) => o.pose(),
            Odometer::Mapped(o) => o.pose(),
        }
    }
}

/// Nearest-rank percentile of sorted values; 0 for none.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let k = ((sorted.len() as f64 * p).ceil() as usize).clamp(1, sorted.len()) - 1;
    (sorted[k] * 100.0).round() / 100.0
}
