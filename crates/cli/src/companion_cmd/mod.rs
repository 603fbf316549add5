//! `plumbline companion`: Plumbline as a companion computer beside PX4 or ArduPilot. A lidar's
//! revolutions (from its serial port, a raw capture or a CARMEN log) go through the online SLAM,
//! and every revolution's pose goes to the autopilot as MAVLink ODOMETRY, with the obstacles
//! around the vehicle as OBSTACLE_DISTANCE and a HEARTBEAT every second.

mod fix;
mod mavlink_out;
mod pipeline;
mod source;

use crate::lidar_cmd::BAUD_RANGE;
use crate::log_args::LogArgs;
use crate::numeric::{within, Range};
use crate::report::{print_summary, CliError, CliResult};
use crate::view_args::{self, ViewArgs};
use crate::view_feed::{Status, ViewFeed};
use clap::{ArgGroup, Args};
use pipeline::{AutopilotLink, Companion};
use plumbline_io::link_port::{Endpoint, LinkPort};
use plumbline_io::serial::{Device, RecordOptions};
use plumbline_slam::{local_map_cells, Slam, SlamConfig};
use plumbline_view::View;
use serde_json::{json, Value};
use source::{each_revolution, Pacer, Source, SourceEnd};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Half side of the web view's map around the start (m): a building's floor.
const VIEW_MAP_HALF_SIDE_M: f64 = 50.0;

/// A live run with no `--duration` lasts until the lidar stops (or the process is stopped).
const FOREVER: Duration = Duration::from_secs(100 * 365 * 24 * 3600);

#[derive(Args)]
#[command(group(ArgGroup::new("input").required(true).args(["port", "replay", "replay_log"])))]
pub struct CompanionArgs {
    /// The lidar: xv11 | xv11-old | urg | rplidar (for --port and --replay).
    #[arg(long)]
    lidar: Option<Device>,
    /// The lidar's serial port, e.g. /dev/ttyUSB0.
    #[arg(long)]
    port: Option<String>,
    /// The lidar's line speed (default: the device's). Valid range: [1200, 4000000].
    #[arg(long, value_parser = within::<u32>(BAUD_RANGE))]
    baud: Option<u32>,
    /// Play a raw capture of the lidar (`plumbline lidar record`) instead of a live port.
    #[arg(long, value_name = "CAPTURE")]
    replay: Option<PathBuf>,
    /// Play a CARMEN log's scans instead of a live port.
    #[arg(long, value_name = "LOG")]
    replay_log: Option<PathBuf>,
    /// Where MAVLink goes: udpout:HOST:PORT or serial:DEVICE:BAUD (the autopilot's telemetry
    /// port).
    #[arg(long, value_name = "ENDPOINT", value_parser = Endpoint::parse)]
    mavlink: Endpoint,
    /// MAVLink system id: the autopilot's own (the companion is a component of the vehicle).
    /// Valid range: [1, 255].
    #[arg(long, default_value_t = 1, value_parser = within::<u32>(Range::closed(1.0, 255.0)))]
    sysid: u32,
    /// Play a replay at the pace of its timestamps (default: as fast as it decodes).
    #[arg(long)]
    realtime: bool,
    /// Seconds to run on a live port (default: until the lidar stops). Valid range: (0, 31536000].
    #[arg(long, value_parser = within::<f64>(Range::above(0.0, 31_536_000.0)))]
    duration: Option<f64>,
    /// Seconds after which the autopilot's estimate (ODOMETRY, or LOCAL_POSITION_NED with
    /// ATTITUDE, read back on the --mavlink port) is too old to guess the SLAM's motion from;
    /// without a fresh one the SLAM guesses from the lidar alone. Valid range: (0, 60].
    #[arg(long, default_value_t = 0.5, value_parser = within::<f64>(Range::above(0.0, 60.0)))]
    estimate_timeout: f64,
    /// Seconds of silence after which the lidar's port counts as dead. Valid range: (0, 3600].
    #[arg(long, default_value_t = 2.0, value_parser = within::<f64>(Range::above(0.0, 3600.0)))]
    idle_timeout: f64,
    #[command(flatten)]
    log_args: LogArgs,
    #[command(flatten)]
    view: ViewArgs,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

fn lidar(a: &CompanionArgs, input: &str) -> Result<Device, CliError> {
    a.lidar.ok_or_else(|| {
        CliError(format!(
            "{input} needs --lidar (one of {})",
            Device::NAMES.join(", ")
        ))
    })
}

fn source(a: &CompanionArgs) -> Result<Source, CliError> {
    if let Some(path) = &a.replay_log {
        return Ok(Source::Log {
            path: path.clone(),
            options: a.log_args.options(),
        });
    }
    if let Some(path) = &a.replay {
        let device = lidar(a, "--replay")?;
        return Ok(Source::Capture {
            path: path.clone(),
            device,
            baud: a.baud.unwrap_or(device.default_baud()),
        });
    }
    let port = a.port.clone().unwrap_or_default();
    let device = lidar(a, "--port")?;
    let seconds = |s: f64| Duration::try_from_secs_f64(s).map_err(|e| CliError(e.to_string()));
    Ok(Source::Port(RecordOptions {
        device,
        port,
        baud: a.baud.unwrap_or(device.default_baud()),
        duration: a.duration.map(seconds).transpose()?.unwrap_or(FOREVER),
        idle_timeout: seconds(a.idle_timeout)?,
    }))
}

pub fn run(a: CompanionArgs) -> CliResult {
    if a.view.view_token.is_some() {
        return Err(CliError(
            "--view-token: the companion's view is read-only; arming, landing and the kill \
             switch belong to the autopilot and its ground station"
                .into(),
        ));
    }
    let source = source(&a)?;
    let live = matches!(source, Source::Port(_));
    let sysid = u8::try_from(a.sysid).map_err(|e| CliError(format!("--sysid: {e}")))?;
    let port = LinkPort::open(&a.mavlink)
        .map_err(|e| CliError(format!("--mavlink {:?}: cannot open: {e}", a.mavlink)))?;
    // A CARMEN log's beams are valid as the log says; a device's from its datasheet on.
    let min_range_m = a
        .lidar
        .filter(|_| a.replay_log.is_none())
        .map_or(0.0, Device::min_range_m);
    let mut link = mavlink_out::MavlinkOut::new(port, sysid, min_range_m, a.estimate_timeout);
    let view = a.view.start()?;
    let mut summary = run_with(&source, live, a.realtime && !live, &mut link, view.as_ref())?;
    let c = link.port().counters();
    if let Value::Object(map) = &mut summary {
        map.insert("mavlink_bytes_sent".into(), c.sent_bytes.into());
        map.insert("mavlink_send_errors".into(), c.send_errors.into());
        if let Some(v) = &view {
            map.insert("view".into(), view_args::summary(v));
        }
    }
    print_summary(&summary, a.json);
    // A lidar port that failed mid-run: the run up to then was sent and summarised, and the
    // exit says it did not end as asked.
    match summary["failure"].as_str() {
        Some(f) => Err(CliError(format!("{f}; the run up to then was sent"))),
        None => Ok(()),
    }
}

/// The whole run over any link: a live port runs the SLAM backend on its own thread, as it
/// must to keep up; a replay runs it inline so the same input gives the same output. With a
/// `view`, each revolution's pose and scan go to the web view too (read-only: the companion
/// knows no flight mode, battery or height).
fn run_with<L: AutopilotLink>(
    source: &Source,
    live: bool,
    realtime: bool,
    link: L,
    view: Option<&View>,
) -> Result<Value, CliError> {
    let wall = Instant::now();
    let config = SlamConfig::in_flight();
    let mut cells = local_map_cells(&config);
    let slam = Slam::new(config, &mut cells, live).map_err(|e| CliError(e.0))?;
    let mut companion = Companion::new(slam, link);
    let mut span: Option<(f64, f64)> = None;
    let mut feed = view.map(|_| ViewFeed::new(VIEW_MAP_HALF_SIDE_M));
    let end: SourceEnd = each_revolution(source, realtime.then(Pacer::new), |rec| {
        companion.revolution(rec)?;
        let t = rec.timestamp_s;
        if let (Some(view), Some(feed), Some(fix)) = (view, &mut feed, companion.last_fix) {
            let [x, y] = fix.position_m.map(f64::from);
            let status = Status {
                battery_v: None,
                mode: None,
                failsafe: None,
            };
            let pose = [x, y, 0.0, f64::from(fix.yaw_rad)];
            let valid = fix.quality_pct.is_some();
            feed.update(view, t, pose, valid, Some(companion.beams()), status);
        }
        span = Some((span.map_or(t, |s| s.0), t));
        Ok(())
    })?;
    if companion.empty_scans > 0 {
        eprintln!(
            "plumbline: {} of {} revolutions had no valid beam (lidar covered or stopped?); \
             each was sent as lost (quality -1)",
            companion.empty_scans, companion.scans
        );
    }
    let g = companion.guesses;
    if g.guessed == 0 && companion.scans > 2 {
        eprintln!(
            "plumbline: no revolution got a motion guess from the autopilot's estimate \
             (missing {}, stale {}, invalid {}, broken {}); the SLAM guessed from the lidar \
             alone. Stream LOCAL_POSITION_NED and ATTITUDE, or ODOMETRY, to this port.",
            g.missing, g.stale, g.invalid, g.discontinuities
        );
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let duration = span.map_or(0.0, |(a, b)| b - a);
    let mut summary = companion.summary();
    if let Value::Object(map) = &mut summary {
        let extra = json!({
            "wall_s": wall_s,
            "realtime_factor": if wall_s > 0.0 { duration / wall_s } else { 0.0 },
            "stopped_by_silence": end.stopped_by_silence,
            "failure": end.failure,
            "packets_ok": end.decode.as_ref().map(|d| d.stats.packets_ok),
            "bad_checksum": end.decode.as_ref().map(|d| d.stats.bad_checksum),
            "skipped_bytes": end.decode.as_ref().map(|d| d.stats.skipped_bytes),
        });
        if let Value::Object(extra) = extra {
            map.extend(extra);
        }
    }
    Ok(summary)
}
