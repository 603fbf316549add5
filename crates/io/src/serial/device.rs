//! One switch over the core decoders, so callers name a device and get CARMEN records.

use crate::carmen::LaserRecord;
use plumbline_core::lidar::rplidar::{RplidarConfig, RplidarDecoder, RplidarRevolution};
use plumbline_core::lidar::scip::{ScipDecoder, ScipScan, UrgConfig};
use plumbline_core::lidar::scip_command::{write_command, Command, Encoding};
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
    /// Hokuyo URG-04LX speaking SCIP 2.0 (MD/MS/GD/GS replies).
    Urg,
    /// Slamtec RPLIDAR A1/A2 standard scan.
    Rplidar,
}

impl Device {
    pub const NAMES: &'static [&'static str] = &["xv11", "xv11-old", "urg", "rplidar"];

    /// The device's usual baud rate: the default for recording and for stamping file decodes.
    pub fn default_baud(self) -> u32 {
        match self {
            Device::Xv11 | Device::Xv11Old | Device::Urg | Device::Rplidar => 115_200,
        }
    }

    /// The nearest distance the device measures reliably (m), from its datasheet: nearer
    /// returns say nothing about obstacles.
    pub fn min_range_m(self) -> f32 {
        match self {
            Device::Xv11 | Device::Xv11Old => 0.06,
            Device::Urg => UrgConfig::URG_04LX.min_range_mm as f32 / 1000.0,
            Device::Rplidar => 0.15,
        }
    }
}

impl FromStr for Device {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "xv11" => Ok(Device::Xv11),
            "xv11-old" => Ok(Device::Xv11Old),
            "urg" => Ok(Device::Urg),
            "rplidar" => Ok(Device::Rplidar),
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
            Device::Urg => 2,
            Device::Rplidar => 3,
        };
        f.write_str(Device::NAMES[i])
    }
}

/// Bytes that start and stop a device's stream. The XV-11 streams whenever its motor turns; the
/// URG streams after `MD` (steps 44..=725, every scan, until `QT`); the RPLIDAR after `SCAN`
/// (`A5 20`, ended by `STOP`, `A5 25`).
pub fn stream_commands(device: Device) -> (Vec<u8>, Vec<u8>) {
    match device {
        Device::Xv11 | Device::Xv11Old => (Vec::new(), Vec::new()),
        Device::Urg => {
            let md = Command::Stream {
                start: 44,
                end: 725,
                cluster: 0,
                interval: 0,
                scans: 0,
                encoding: Encoding::ThreeChar,
            };
            let mut buf = [0u8; 32];
            // The parameters above are in range and the buffer holds any command.
            let n = write_command(&md, &mut buf).unwrap_or(0);
            (buf[..n].to_vec(), b"QT\n".to_vec())
        }
        Device::Rplidar => (vec![0xA5, 0x20], vec![0xA5, 0x25]),
    }
}

/// A decoded revolution as an equally spaced CARMEN record (timestamp 0 until the caller stamps
/// it), plus what the record cannot hold.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedScan {
    pub record: LaserRecord,
    pub rpm: Option<f32>,
    /// Stream offset of the revolution's first byte (XV-11), or of the byte that completed it
    /// (URG, RPLIDAR, whose decoders keep no offsets): with a data rate, a clock for captures.
    pub first_offset: u64,
    /// The device's own data rate while sending this revolution, where the stream fixes it: the
    /// XV-11 sends 90 packets of 22 bytes a turn (33 bytes/s per RPM), an RPLIDAR 5 bytes a
    /// sample. A device may pause between bytes, so the line rate (baud / 10) overestimates it.
    pub bytes_per_s: Option<f64>,
    /// The device's own clock for this scan (the URG's millisecond timestamp), seconds.
    pub device_time_s: Option<f64>,
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
/// 90 packets of 22 bytes.
const XV11_BYTES_PER_TURN: f64 = 1980.0;

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
        bytes_per_s: rev
            .rpm()
            .map(|rpm| XV11_BYTES_PER_TURN * f64::from(rpm) / 60.0),
        device_time_s: None,
    }
}

fn from_urg(scan: ScipScan<URG_STEPS>, offset: u64) -> DecodedScan {
    let cfg = UrgConfig::URG_04LX;
    let start_deg = cfg.step_angle_rad(scan.value_step(0)).to_degrees();
    let step_deg = f32::from(scan.cluster) * 360.0 / f32::from(cfg.steps_per_rev);
    // Values above DMAX are invalid; a max range just past it keeps them invalid on reading.
    let max_m = cfg.max_range_mm as f32 / 1000.0 + 0.001;
    let record = record_from_scan(&scan.to_scan(&cfg), start_deg, step_deg, max_m);
    DecodedScan {
        record,
        rpm: Some(60.0 / cfg.scan_period_s),
        first_offset: offset,
        bytes_per_s: None,
        device_time_s: Some(f64::from(scan.timestamp_ms) / 1000.0),
    }
}

/// RPLIDAR nodes fall at uneven angles; CARMEN needs equal spacing, so each node goes to the
/// nearest whole degree on the XV-11's grid (-179..=180), the node nearest the bin centre
/// winning. Bins no node reached are invalid.
fn from_rplidar(rev: RplidarRevolution<RPLIDAR_NODES>, offset: u64) -> DecodedScan {
    let cfg = RplidarConfig::A1;
    let scan = rev.to_scan(&cfg);
    let mut ranges = vec![0.0f32; 360];
    let mut valid = vec![false; 360];
    let mut miss = vec![f32::INFINITY; 360];
    for b in scan.beams().iter().filter(|b| b.valid) {
        let deg = b.angle_rad.to_degrees();
        let bin = deg.round();
        let j = ((bin as i32 + 179).rem_euclid(360)) as usize;
        if (deg - bin).abs() < miss[j] {
            miss[j] = (deg - bin).abs();
            ranges[j] = b.range_m;
            valid[j] = true;
        }
    }
    let mut record = LaserRecord::new(
        0.0,
        (-179f32).to_radians(),
        1f32.to_radians(),
        cfg.max_range_m,
        ranges,
    );
    record.valid = valid;
    DecodedScan {
        record,
        rpm: rev.rpm(&cfg),
        first_offset: offset,
        bytes_per_s: Some(5.0 / f64::from(cfg.sample_period_s)),
        device_time_s: None,
    }
}

/// URG-04LX: steps 0..=768.
const URG_STEPS: usize = 769;
/// RPLIDAR standard scan: about 360-400 nodes a turn; twice that for margin.
const RPLIDAR_NODES: usize = 800;

/// Any device's decoder. Boxed: the decoders hold whole revolutions.
pub enum DeviceDecoder {
    Xv11(Box<Xv11Decoder>),
    Xv11Old(Box<Xv11OldDecoder>),
    Urg(Box<ScipDecoder<URG_STEPS>>),
    Rplidar(Box<RplidarDecoder<RPLIDAR_NODES>>),
}

impl DeviceDecoder {
    pub fn new(device: Device) -> Self {
        match device {
            Device::Xv11 => DeviceDecoder::Xv11(Box::default()),
            Device::Xv11Old => DeviceDecoder::Xv11Old(Box::default()),
            Device::Urg => DeviceDecoder::Urg(Box::default()),
            Device::Rplidar => DeviceDecoder::Rplidar(Box::default()),
        }
    }

    pub fn push(&mut self, byte: u8) -> Option<DecodedScan> {
        match self {
            DeviceDecoder::Xv11(d) => d.push(byte).map(from_xv11),
            DeviceDecoder::Xv11Old(d) => d.push(byte).map(from_xv11),
            DeviceDecoder::Urg(d) => d.push(byte).map(|s| from_urg(s, d.stats().bytes)),
            DeviceDecoder::Rplidar(d) => d.push(byte).map(|r| from_rplidar(r, d.stats().bytes)),
        }
    }

    /// Ends the stream, handing out a last partial or unconfirmed revolution.
    pub fn finish(&mut self) -> Option<DecodedScan> {
        match self {
            DeviceDecoder::Xv11(d) => d.finish().map(from_xv11),
            DeviceDecoder::Xv11Old(d) => d.finish().map(from_xv11),
            DeviceDecoder::Urg(_) => None, // a SCIP scan is complete only at its closing line
            DeviceDecoder::Rplidar(d) => d.finish().map(|r| from_rplidar(r, d.stats().bytes)),
        }
    }

    pub fn stats(&self) -> DecodeStats {
        match self {
            DeviceDecoder::Xv11(d) => d.stats(),
            DeviceDecoder::Xv11Old(d) => d.stats(),
            DeviceDecoder::Urg(d) => d.stats(),
            DeviceDecoder::Rplidar(d) => d.stats(),
        }
    }
}
