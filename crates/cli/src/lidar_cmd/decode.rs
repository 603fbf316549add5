//! `plumbline lidar decode --device D CAPTURE [--out LOG]`.

use super::{require_frames, summary_json, BAUD_RANGE};
use crate::numeric::within;
use crate::report::{print_summary, CliError, CliResult};
use clap::Args;
use plumbline_io::carmen::write_robotlaser1;
use plumbline_io::input::open_input;
use plumbline_io::output::{check_distinct, OutputFile};
use plumbline_io::serial::{decode_stream, Device};
use serde_json::Value;
use std::path::PathBuf;

/// Decodes as it reads, with bounded memory: a capture with no valid frame in its first MiB
/// (or in any MiB after its last frame) is refused there rather than read to its end.
#[derive(Args)]
pub struct DecodeArgs {
    /// xv11 | xv11-old | urg | rplidar
    #[arg(long)]
    device: Device,
    /// The raw capture (gzip-compressed is fine).
    capture: PathBuf,
    /// Write the scans as a CARMEN ROBOTLASER1 log (replaced only when the decode succeeds).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Line speed the capture was taken at; stamps scans by byte position (default: the device's).
    /// Valid range: [1200, 4000000].
    #[arg(long, value_parser = within::<u32>(BAUD_RANGE))]
    baud: Option<u32>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: DecodeArgs) -> CliResult {
    if let Some(out) = &a.out {
        check_distinct(&[("CAPTURE", &a.capture)], &[("--out", out)])?;
    }
    let input = open_input(&a.capture)?;
    let mut log = a.out.as_deref().map(OutputFile::stage).transpose()?;
    let baud = a.baud.unwrap_or(a.device.default_baud());
    let summary = decode_stream(a.device, input.reader, &input.name, baud, |scan| {
        if let Some(w) = log.as_mut() {
            write_robotlaser1(w, &scan.record, "plumbline").map_err(|e| w.error(e))?;
        }
        Ok::<_, CliError>(true)
    })?;
    require_frames(&input.name, a.device, &summary)?;
    if let Some(w) = log {
        w.commit()?;
    }
    let mut map = summary_json(a.device, &summary);
    map.insert("capture".into(), a.capture.display().to_string().into());
    map.insert("out".into(), a.out.map(|p| p.display().to_string()).into());
    print_summary(&Value::Object(map), a.json);
    Ok(())
}
