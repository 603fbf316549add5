//! CARMEN log reader: `FLASER`, `ROBOTLASER1`, `ODOM`, `PARAM` and comments; `.gz` transparently.
//!
//! Every other record type (NEFF, SYNC, RAWLASER…) is counted and passed over: benchmark logs mix
//! them in and none of them carries a scan. A malformed line is an error naming the file and the
//! line, unless `skip_bad_lines` asks for it to be counted and reported instead.

use super::fov::FovRule;
use super::{LaserRecord, OdomPose};
use std::fmt;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// FLASER stores no max range; SICK scanners report "no return" as 81.83 or 81.91 m
/// (13-bit centimetres), so anything at or above this is a miss, not a hit.
pub const FLASER_MAX_RANGE_M: f32 = 81.0;

/// How to read a log.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    pub fov: FovRule,
    /// Readings at or beyond this are invalid (FLASER has no stored max range).
    pub flaser_max_range_m: f32,
    /// Count and pass over malformed lines instead of failing on the first.
    pub skip_bad_lines: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            fov: FovRule::Conventional,
            flaser_max_range_m: FLASER_MAX_RANGE_M,
            skip_bad_lines: false,
        }
    }
}

/// One odometry reading from an `ODOM` line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdomRecord {
    pub timestamp_s: f64,
    pub pose: OdomPose,
}

/// What the reader saw, so nothing is dropped silently.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadStats {
    pub lines: usize,
    pub flaser: usize,
    pub robotlaser1: usize,
    pub odom: usize,
    pub params: usize,
    pub comments: usize,
    /// Records of other types (NEFF, SYNC, …), passed over.
    pub other_records: usize,
    /// Malformed lines passed over because `skip_bad_lines` was set.
    pub bad_lines: usize,
    /// Scans whose timestamp is earlier than the scan before them (kept, in file order).
    pub non_monotonic_scans: usize,
    /// The first malformed line passed over, for the report.
    pub first_bad_line: Option<String>,
}

/// A log read into memory.
#[derive(Clone, Debug, Default)]
pub struct CarmenLog {
    pub scans: Vec<LaserRecord>,
    /// The 1-based line each scan was read from, so later checks can name it.
    pub scan_lines: Vec<usize>,
    pub odometry: Vec<OdomRecord>,
    pub params: Vec<(String, String)>,
    pub stats: ReadStats,
}

/// A failure that names where it happened.
#[derive(Debug)]
pub struct ReadError {
    pub file: String,
    /// 1-based line number; 0 when the file itself could not be read.
    pub line: usize,
    pub message: String,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}:{}: {}", self.file, self.line, self.message)
        }
    }
}

impl std::error::Error for ReadError {}

/// Opens a text file for reading, decompressing it when its name ends in `.gz`; every reader of
/// the project's files goes through here so they all take gzip the same way.
pub fn open_text(path: &Path) -> Result<(String, BufReader<Box<dyn Read>>), ReadError> {
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| ReadError {
        file: name.clone(),
        line: 0,
        message: e.to_string(),
    })?;
    let reader: Box<dyn Read> = if name.ends_with(".gz") {
        Box::new(flate2::read::MultiGzDecoder::new(file))
    } else {
        Box::new(file)
    };
    Ok((name, BufReader::new(reader)))
}

/// Reads a log file, decompressing it when its name ends in `.gz`.
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<CarmenLog, ReadError> {
    let (name, reader) = open_text(path)?;
    parse_log(reader, &name, opts)
}

/// Parses a log from any reader; `name` is used in error messages.
pub fn parse_log<R: BufRead>(
    reader: R,
    name: &str,
    opts: &ReadOptions,
) -> Result<CarmenLog, ReadError> {
    let mut log = CarmenLog::default();
    let mut last_scan_time = f64::NEG_INFINITY;
    for (i, line) in reader.lines().enumerate() {
        let line_no = i + 1;
        let err = |message: String| ReadError {
            file: name.to_string(),
            line: line_no,
            message,
        };
        let line = line.map_err(|e| err(format!("cannot read: {e}")))?;
        log.stats.lines += 1;
        match parse_line(&line, opts) {
            Ok(Parsed::Scan(rec, is_flaser)) => {
                if rec.timestamp_s < last_scan_time {
                    log.stats.non_monotonic_scans += 1;
                }
                last_scan_time = rec.timestamp_s;
                *(if is_flaser {
                    &mut log.stats.flaser
                } else {
                    &mut log.stats.robotlaser1
                }) += 1;
                log.scans.push(rec);
                log.scan_lines.push(line_no);
            }
            Ok(Parsed::Odom(o)) => {
                log.stats.odom += 1;
                log.odometry.push(o);
            }
            Ok(Parsed::Param(k, v)) => {
                log.stats.params += 1;
                log.params.push((k, v));
            }
            Ok(Parsed::Comment) => log.stats.comments += 1,
            Ok(Parsed::Other) => log.stats.other_records += 1,
            Err(message) if opts.skip_bad_lines => {
                log.stats.bad_lines += 1;
                log.stats
                    .first_bad_line
                    .get_or_insert_with(|| format!("{name}:{line_no}: {message}"));
            }
            Err(message) => return Err(err(message)),
        }
    }
    Ok(log)
}

enum Parsed {
    Scan(LaserRecord, bool),
    Odom(OdomRecord),
    Param(String, String),
    Comment,
    Other,
}

fn parse_line(line: &str, opts: &ReadOptions) -> Result<Parsed, String> {
    let mut fields = Fields {
        inner: line.split_ascii_whitespace(),
        taken: 0,
    };
    let Some(kind) = fields.inner.next() else {
        return Ok(Parsed::Comment);
    };
    match kind {
        k if k.starts_with('#') => Ok(Parsed::Comment),
        "FLASER" => parse_flaser(&mut fields, opts).map(|r| Parsed::Scan(r, true)),
        "ROBOTLASER1" => parse_robotlaser1(&mut fields).map(|r| Parsed::Scan(r, false)),
        "ODOM" => parse_odom(&mut fields).map(Parsed::Odom),
        "PARAM" => {
            let key = fields.text("parameter name")?.to_string();
            let value = fields.text("parameter value")?.to_string();
            Ok(Parsed::Param(key, value))
        }
        _ => Ok(Parsed::Other),
    }
}

/// Whitespace fields with errors that say which field was missing or wrong.
struct Fields<'a> {
    inner: std::str::SplitAsciiWhitespace<'a>,
    taken: usize,
}

impl<'a> Fields<'a> {
    fn text(&mut self, what: &str) -> Result<&'a str, String> {
        self.taken += 1;
        self.inner
            .next()
            .ok_or_else(|| format!("line ends before {what} (field {})", self.taken + 1))
    }

    fn num<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, String> {
        let t = self.text(what)?;
        t.parse()
            .map_err(|_| format!("{what} is not a number: {t:?} (field {})", self.taken + 1))
    }

    /// A float that must be finite: NaN poses and timestamps are garbage, not data.
    fn finite(&mut self, what: &str) -> Result<f64, String> {
        let v: f64 = self.num(what)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!(
                "{what} is not finite: {v} (field {})",
                self.taken + 1
            ))
        }
    }

    fn count(&mut self, what: &str, max: usize) -> Result<usize, String> {
        let n: usize = self.num(what)?;
        if n > max {
            return Err(format!("{what} {n} is larger than {max}"));
        }
        Ok(n)
    }

    /// Fields not yet taken; the counts in a record are checked against this before trusting them.
    fn remaining(&self) -> usize {
        self.inner.clone().count()
    }

    /// A record's beam count fixes how many fields follow it; a count that disagrees with the line
    /// would otherwise shift every later field (a range read as a pose, a pose as a timestamp).
    fn expect_remaining(&self, record: &str, counts: &str, expected: usize) -> Result<(), String> {
        let found = self.remaining();
        if found == expected {
            return Ok(());
        }
        Err(format!(
            "{record}: {counts} make {expected} fields after field {}, but the line has {found}; \
             the count disagrees with the readings (truncated or corrupted line?)",
            self.taken + 1
        ))
    }

    /// Every field must have been read: trailing fields mean the record is not what it claims.
    fn end(&mut self, record: &str) -> Result<(), String> {
        match self.inner.next() {
            None => Ok(()),
            Some(extra) => Err(format!(
                "{record}: unexpected field {} {extra:?} after the logger timestamp",
                self.taken + 2
            )),
        }
    }

    /// Range readings; NaN or infinite readings are kept and become invalid beams.
    fn ranges(&mut self, n: usize) -> Result<Vec<f32>, String> {
        (0..n)
            .map(|i| self.num::<f32>(&format!("range reading {}", i + 1)))
            .collect()
    }

    fn pose(&mut self, what: &str) -> Result<OdomPose, String> {
        Ok(OdomPose {
            x_m: self.finite(&format!("{what} x"))?,
            y_m: self.finite(&format!("{what} y"))?,
            theta_rad: self.finite(&format!("{what} theta"))?,
        })
    }

    /// `ipc_timestamp hostname logger_timestamp`, closing every record.
    fn stamps(&mut self) -> Result<(f64, String), String> {
        let text = self.text("ipc_timestamp")?;
        let t: f64 = text
            .parse()
            .map_err(|_| format!("ipc_timestamp is not a number: {text:?}"))?;
        if !t.is_finite() {
            return Err(format!("ipc_timestamp is not finite: {text:?}"));
        }
        self.text("hostname")?;
        self.finite("logger_timestamp")?;
        Ok((t, text.to_string()))
    }
}

/// Beams per scan we accept; far beyond any 2-D lidar (a UTM-30LX has 1081).
const MAX_BEAMS: usize = 100_000;

fn parse_flaser(f: &mut Fields, opts: &ReadOptions) -> Result<LaserRecord, String> {
    let n = f.count("number of readings", MAX_BEAMS)?;
    // readings, robot pose (3), odometry pose (3), ipc_timestamp hostname logger_timestamp
    f.expect_remaining("FLASER", &format!("{n} readings"), n + 9)?;
    let ranges = f.ranges(n)?;
    let pose = f.pose("robot pose")?;
    f.pose("odometry pose")?;
    let (t, text) = f.stamps()?;
    f.end("FLASER")?;
    let (start, inc) = opts.fov.beam_layout(n);
    let mut rec = LaserRecord::new(t, start, inc, opts.flaser_max_range_m, ranges);
    rec.timestamp_text = text;
    rec.odom = Some(pose);
    Ok(rec)
}

fn parse_robotlaser1(f: &mut Fields) -> Result<LaserRecord, String> {
    f.text("laser_type")?;
    let start = f.finite("start_angle")? as f32;
    f.finite("field of view")?;
    let inc = f.finite("angular resolution")? as f32;
    let max_range = f.finite("max range")? as f32;
    f.finite("accuracy")?;
    f.text("remission_mode")?;
    let n = f.count("number of readings", MAX_BEAMS)?;
    // after the readings: the remission count, the remissions, laser pose (3), robot pose (3),
    // tv rv forward_safety_dist side_safety_dist turn_axis, and the three stamps
    const CLOSING_FIELDS: usize = 14;
    if f.remaining() < n + 1 + CLOSING_FIELDS {
        f.expect_remaining(
            "ROBOTLASER1",
            &format!("{n} readings"),
            n + 1 + CLOSING_FIELDS,
        )?;
    }
    let ranges = f.ranges(n)?;
    let k = f.count("number of remissions", MAX_BEAMS)?;
    f.expect_remaining(
        "ROBOTLASER1",
        &format!("{n} readings and {k} remissions"),
        k + CLOSING_FIELDS,
    )?;
    for i in 0..k {
        f.num::<f32>(&format!("remission {}", i + 1))?;
    }
    f.pose("laser pose")?;
    let pose = f.pose("robot pose")?;
    for what in [
        "tv",
        "rv",
        "forward_safety_dist",
        "side_safety_dist",
        "turn_axis",
    ] {
        f.finite(what)?;
    }
    let (t, text) = f.stamps()?;
    f.end("ROBOTLASER1")?;
    let max_range = if max_range > 0.0 {
        max_range
    } else {
        FLASER_MAX_RANGE_M
    };
    let mut rec = LaserRecord::new(t, start, inc, max_range, ranges);
    rec.timestamp_text = text;
    rec.odom = Some(pose);
    Ok(rec)
}

fn parse_odom(f: &mut Fields) -> Result<OdomRecord, String> {
    let pose = f.pose("odometry pose")?;
    for what in ["tv", "rv", "accel"] {
        f.finite(what)?;
    }
    let (timestamp_s, _) = f.stamps()?;
    f.end("ODOM")?;
    Ok(OdomRecord { timestamp_s, pose })
}
