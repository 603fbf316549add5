//! `plumbline lidar decode --device D CAPTURE [--out LOG]`.

use super::{read_capture, require_frames, summary_json, write_log, BAUD_RANGE};
use crate::numeric::within;
use crate::report::{print_summary, CliResult};
use clap::Args;
use plumbline_io::serial::{decode_capture, Device};
use serde_json::Value;
use std::path::PathBuf;

#[derive(Args)]
pub struct DecodeArgs {
    /// xv11 | xv11-old | urg | rplidar
    #[arg(long)]
    device: Device,
    /// The raw capture.
    capture: PathBuf,
    /// Write the scans as a CARMEN ROBOTLASER1 log.
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
    let bytes = read_capture(&a.capture)?;
    let (scans, summary) =
        decode_capture(a.device, &bytes, a.baud.unwrap_or(a.device.default_baud()));
    require_frames(&a.capture.display().to_string(), a.device, &summary)?;
    if let Some(out) = &a.out {
        write_log(out, &scans)?;
    }
    let mut map = summary_json(a.device, &summary);
    map.insert("capture".into(), a.capture.display().to_string().into());
    map.insert("out".into(), a.out.map(|p| p.display().to_string()).into());
    print_summary(&Value::Object(map), a.json);
    Ok(())
}
