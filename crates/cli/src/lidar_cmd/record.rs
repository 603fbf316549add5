//! `plumbline lidar record --device D --port PORT [--baud B] [--duration S] --out FILE`:
//! raw bytes to FILE, decoded scans to a CARMEN log beside it (`FILE.log` unless `--log`).

use super::{require_frames, summary_json, BAUD_RANGE};
use crate::numeric::{within, Range};
use crate::report::{print_summary, CliError, CliResult};
use clap::Args;
use plumbline_io::carmen::write_robotlaser1;
use plumbline_io::serial::{record, Device, RecordOptions};
use serde_json::Value;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
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

fn create(path: &PathBuf) -> Result<BufWriter<std::fs::File>, CliError> {
    std::fs::File::create(path)
        .map(BufWriter::new)
        .map_err(|e| CliError(format!("{}: {e}", path.display())))
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
    let mut raw = create(&a.out)?;
    let mut log = create(&log_path)?;
    let recorded = record(&opts, &mut raw, &mut |scan| {
        write_robotlaser1(&mut log, &scan.record, "plumbline")
    })?;
    log.flush()
        .map_err(|e| CliError(format!("{}: {e}", log_path.display())))?;
    let summary = &recorded.summary;
    require_frames(&a.port, a.device, summary)?;
    if recorded.stopped_by_silence {
        eprintln!(
            "plumbline: {}: stream stopped (silent for {} s); recording ended early",
            a.port, a.idle_timeout
        );
    }
    let mut map = summary_json(a.device, summary);
    map.insert(
        "stopped_by_silence".into(),
        recorded.stopped_by_silence.into(),
    );
    map.insert("port".into(), a.port.into());
    map.insert("out".into(), a.out.display().to_string().into());
    map.insert("log".into(), log_path.display().to_string().into());
    print_summary(&Value::Object(map), a.json);
    Ok(())
}
