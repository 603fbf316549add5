//! `plumbline lidar record --device D --port PORT [--baud B] [--duration S] --out FILE`:
//! raw bytes to FILE, decoded scans to a CARMEN log beside it (`FILE.log` unless `--log`).
//!
//! The files are replaced only once the device has sent data, so a wrong port or a device that
//! is off leaves existing files as they were; from then on every chunk read and every scan is
//! flushed as it comes, so a recording that is killed keeps what it had.

use super::{require_frames, summary_json, BAUD_RANGE};
use crate::numeric::{within, Range};
use crate::report::{print_summary, CliError, CliResult};
use clap::Args;
use plumbline_io::carmen::write_robotlaser1;
use plumbline_io::output::{check_distinct, OutputFile};
use plumbline_io::serial::{open_port, DecodedScan, Device, RecordOptions, RecordSink};
use serde_json::Value;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

#[derive(Args)]
pub struct RecordArgs {
    /// xv11 | xv11-old | urg | rplidar
    #[arg(long)]
    device: Device,
    /// Serial port, e.g. /dev/ttyUSB0.
    #[arg(long)]
    port: String,
    /// Line speed (default: the device's). Valid range: [1200, 4000000].
    #[arg(long, value_parser = within::<u32>(BAUD_RANGE))]
    baud: Option<u32>,
    /// Seconds to record. Valid range: (0, 86400].
    #[arg(long, default_value_t = 10.0, value_parser = within::<f64>(Range::above(0.0, 86400.0)))]
    duration: f64,
    /// Seconds of silence after which the port counts as dead. Valid range: (0, 3600].
    #[arg(long, default_value_t = 2.0, value_parser = within::<f64>(Range::above(0.0, 3600.0)))]
    idle_timeout: f64,
    /// Raw capture out.
    #[arg(long)]
    out: PathBuf,
    /// CARMEN log out (default: the capture's name plus `.log`).
    #[arg(long)]
    log: Option<PathBuf>,
    #[arg(long)]
    json: bool,
}

fn seconds(name: &str, s: f64) -> Result<Duration, CliError> {
    Duration::try_from_secs_f64(s)
        .map_err(|_| CliError(format!("--{name} {s}: not a duration in seconds")))
}

/// The capture and its log, staged until the device's first bytes, then written through.
struct Files {
    raw: OutputFile,
    log: OutputFile,
}

/// An I/O error that names the file, since the recorder reports it as it is.
fn named(file: &OutputFile, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("{}: {e}", file.shown()))
}

impl RecordSink for Files {
    fn raw(&mut self, bytes: &[u8]) -> io::Result<()> {
        for f in [&mut self.raw, &mut self.log] {
            if !f.is_published() {
                f.publish().map_err(io::Error::other)?;
            }
        }
        let raw = &mut self.raw;
        raw.write_all(bytes)
            .and_then(|()| raw.flush())
            .map_err(|e| named(raw, e))
    }

    fn scan(&mut self, scan: &DecodedScan) -> io::Result<()> {
        let log = &mut self.log;
        write_robotlaser1(log, &scan.record, "plumbline")
            .and_then(|()| log.flush())
            .map_err(|e| named(log, e))
    }
}

pub fn run(a: RecordArgs) -> CliResult {
    let opts = RecordOptions {
        device: a.device,
        port: a.port.clone(),
        baud: a.baud.unwrap_or(a.device.default_baud()),
        duration: seconds("duration", a.duration)?,
        idle_timeout: seconds("idle-timeout", a.idle_timeout)?,
    };
    let log_path = a.log.unwrap_or_else(|| {
        let mut p = a.out.clone().into_os_string();
        p.push(".log");
        p.into()
    });
    check_distinct(
        &[("--port", Path::new(&a.port))],
        &[("--out", &a.out), ("--log", &log_path)],
    )?;
    let port = open_port(&opts)?;
    let mut files = Files {
        raw: OutputFile::stage(&a.out)?,
        log: OutputFile::stage(&log_path)?,
    };
    let recorded = port.record(&mut files)?;
    let Files { raw, log } = files;
    let committed = raw.commit().and_then(|()| log.commit());
    let summary = &recorded.summary;
    if recorded.stopped_by_silence {
        eprintln!(
            "plumbline: {}: stream stopped (silent for {} s); recording ended early",
            a.port, a.idle_timeout
        );
    }
    let failure = match (recorded.failure, committed) {
        (Some(f), _) => Some(CliError(format!("{f}; the recording up to then is kept"))),
        (None, Err(e)) => Some(e.into()),
        (None, Ok(())) => require_frames(&a.port, a.device, summary).err(),
    };
    let mut map = summary_json(a.device, summary);
    map.insert(
        "stopped_by_silence".into(),
        recorded.stopped_by_silence.into(),
    );
    map.insert("port".into(), a.port.into());
    map.insert("out".into(), a.out.display().to_string().into());
    map.insert("log".into(), log_path.display().to_string().into());
    map.insert(
        "failure".into(),
        failure.as_ref().map(|f| f.0.clone()).into(),
    );
    print_summary(&Value::Object(map), a.json);
    failure.map_or(Ok(()), Err)
}
