//! One switch over the core decoders, so callers name a device and get CARMEN records.

use crate::carmen::LaserRecord;
use plumbline_core::lidar::xv11_old::Xv11OldDecoder;
use plumbline_core::lidar::xv11_revolution::{Revolution, Xv11Decoder};
use plumbline_core::lidar::DecodeStats;
use plumbline_core::scan::Scan;
use std::fmt;
use std::str::FromStr;

/// The lidars Plumbline reads, by their command-line names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Device {
    /// Neato XV-11, firmware 2.4 and later (`0xFA` packets).
    Xv11,
    /// Neato XV-11 before firmware 2.4 (1446-byte frames).
    Xv11Old,
}

impl Device {
    pub const NAMES: &'static [&'static str] = &["xv11", "xv11-old"];

    /// The device's usual baud rate: the default for recording and for stamping file decodes.
    pub fn default_baud(self) -> u32 {
        match self {
            Device::Xv11 | Device::Xv11Old => 115_200,
        }
    }
}

impl FromStr for Device {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "xv11" => Ok(Device::Xv11),
            "xv11-old" => Ok(Device::Xv11Old),
            _ => Err(format!(
                "unknown device '{s}' (expected one of {})",
                Device::NAMES.join(", ")
            )),
        }
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = match self {
            Device::Xv11 => 0,
            Device::Xv11Old => 1,
        };
        f.write_str(Device::NAMES[i])
    }
}

/// A decoded revolution as an equally spaced CARMEN record (timestamp 0 until the caller stamps
/// it), plus what the record cannot hold.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedScan {
    pub record: LaserRecord,
    pub rpm: Option<f32>,
    /// Stream offset of the revolution's first byte; with the baud rate, a clock for captures.
    pub first_offset: u64,
}

impl DecodedScan {
    /// Sets the record's timestamp (seconds) and its text.
    pub fn stamp(&mut self, timestamp_s: f64) {
        self.record.timestamp_s = timestamp_s;
        self.record.timestamp_text = format!("{timestamp_s:.6}");
    }

    pub fn invalid_beams(&self) -> usize {
        self.record.valid.iter().filter(|v| !**v).count()
    }
}

/// XV-11 distances are 14 bits: every encodable reading is below this, so CARMEN's "invalid
/// is written as max range" survives a round trip.
const XV11_MAX_RANGE_M: f32 = 16.384;

fn record_from_scan<const N: usize>(
    scan: &Scan<N>,
    start_deg: f32,
    step_deg: f32,
    max_m: f32,
) -> LaserRecord {
    let ranges = scan.beams().iter().map(|b| b.range_m).collect();
    let mut rec = LaserRecord::new(
        scan.stamp_s,
        start_deg.to_radians(),
        step_deg.to_radians(),
        max_m,
        ranges,
    );
    rec.valid = scan.beams().iter().map(|b| b.valid).collect();
    rec
}

fn from_xv11(rev: Revolution) -> DecodedScan {
    let scan = rev.to_scan(0.0);
    let record = record_from_scan(
        &scan,
        Revolution::START_ANGLE_DEG,
        Revolution::INCREMENT_DEG,
        XV11_MAX_RANGE_M,
    );
    DecodedScan {
        record,
        rpm: rev.rpm(),
        first_offset: rev.first_offset,
    }
}

/// Any device's decoder. Boxed: the decoders hold whole revolutions.
pub enum DeviceDecoder {
    Xv11(Box<Xv11Decoder>),
    Xv11Old(Box<Xv11OldDecoder>),
}

impl DeviceDecoder {
    pub fn new(device: Device) -> Self {
        match device {
            Device::Xv11 => DeviceDecoder::Xv11(Box::default()),
            Device::Xv11Old => DeviceDecoder::Xv11Old(Box::default()),
        }
    }

    pub fn push(&mut self, byte: u8) -> Option<DecodedScan> {
        match self {
            DeviceDecoder::Xv11(d) => d.push(byte).map(from_xv11),
            DeviceDecoder::Xv11Old(d) => d.push(byte).map(from_xv11),
        }
    }

    /// Ends the stream, handing out a last partial or unconfirmed revolution.
    pub fn finish(&mut self) -> Option<DecodedScan> {
        match self {
            DeviceDecoder::Xv11(d) => d.finish().map(from_xv11),
            DeviceDecoder::Xv11Old(d) => d.finish().map(from_xv11),
        }
    }

    pub fn stats(&self) -> DecodeStats {
        match self {
            DeviceDecoder::Xv11(d) => d.stats(),
            DeviceDecoder::Xv11Old(d) => d.stats(),
        }
    }
}
