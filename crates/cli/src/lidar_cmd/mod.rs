//! `plumbline lidar`: decode raw captures to CARMEN logs, record from a serial port, plot one
//! revolution. The decoding itself lives in `plumbline-core` (sans-I/O) and `plumbline-io`.

mod decode;
mod plot;
mod record;

use crate::numeric::Range;
use crate::report::{CliError, CliResult};
use clap::{Args, Subcommand};
use plumbline_io::serial::{DecodeSummary, Device};
use serde_json::{json, Map, Value};

/// Line speeds a serial lidar can be run at; outside this, stamps by byte position mean nothing.
pub(crate) const BAUD_RANGE: Range = Range::closed(1200.0, 4_000_000.0);

#[derive(Args)]
pub struct LidarArgs {
    #[command(subcommand)]
    command: LidarCommand,
}

#[derive(Subcommand)]
enum LidarCommand {
    /// Turn a raw capture (the bytes a device sent) into a CARMEN ROBOTLASER1 log.
    Decode(decode::DecodeArgs),
    /// Record raw bytes from a serial port, and the decoded scans as a CARMEN log.
    Record(record::RecordArgs),
    /// Draw one revolution of a raw capture as a PNG.
    Plot(plot::PlotArgs),
}

pub fn run(args: LidarArgs) -> CliResult {
    match args.command {
        LidarCommand::Decode(a) => decode::run(a),
        LidarCommand::Record(a) => record::run(a),
        LidarCommand::Plot(a) => plot::run(a),
    }
}

/// The summary keys every lidar subcommand reports (`DESIGN.md` CLI contract plus fault counts).
fn summary_json(device: Device, summary: &DecodeSummary) -> Map<String, Value> {
    let s = &summary.stats;
    let v = json!({
        "device": device.to_string(),
        "bytes": s.bytes,
        "packets_ok": s.packets_ok,
        "bad_checksum": s.bad_checksum,
        "malformed": s.malformed,
        "skipped_bytes": s.skipped_bytes,
        "revolutions": s.revolutions,
        "out_of_order": s.out_of_order,
        "missing_packets": s.missing_packets,
        "overflow": s.overflow,
        "implausible_revolutions": s.implausible,
        "rpm_median": summary.rpm_median,
        "invalid_beams": summary.invalid_beams,
    });
    match v {
        Value::Object(map) => map,
        _ => Map::new(),
    }
}

/// A capture with bytes but not one good frame is an error, not an empty log: the usual causes
/// are the wrong `--device` or a capture taken at the wrong baud rate. So is one whose frames
/// pass their checks but make only revolutions the device cannot send (weak checks pass foreign
/// bytes by chance); when most revolutions are like that, a warning says so.
pub(crate) fn require_frames(what: &str, device: Device, summary: &DecodeSummary) -> CliResult {
    let s = &summary.stats;
    if s.bytes > 0 && s.packets_ok == 0 && s.implausible == 0 {
        return Err(CliError(format!(
            "{what}: {} bytes but no valid {device} frame (wrong --device, or the wrong baud rate?)",
            s.bytes
        )));
    }
    let assembled = s.revolutions + s.implausible;
    let verdict = format!(
        "{what}: these bytes do not look like {device} data: {} of {assembled} revolutions plausible \
         (speed, beams per turn, angles); is --device right?",
        s.revolutions
    );
    if s.revolutions == 0 && s.implausible > 0 {
        return Err(CliError(verdict));
    }
    if s.implausible > s.revolutions {
        eprintln!("plumbline: WARNING: {verdict}");
    }
    Ok(())
}
