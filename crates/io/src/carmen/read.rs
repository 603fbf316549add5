//! CARMEN log reader: `FLASER`, `ROBOTLASER1`, `ODOM`, `PARAM` and comments, one record at a
//! time; gzip transparently.
//!
//! Every other record type (NEFF, SYNC, RAWLASER…) is counted and passed over: benchmark logs mix
//! them in and none of them carries a scan. A malformed line is an error naming the file and the
//! line, unless `skip_bad_lines` asks for it to be counted and reported instead.

use super::fov::FovRule;
use super::line::{parse_line, Parsed};
use super::{LaserRecord, OdomPose};
use crate::input::{open_input, ReadProgress, TextLines};
use std::fmt;
use std::io::BufRead;
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

/// A log read one record at a time, so memory stays bounded whatever the file's length.
pub struct LogReader<R> {
    lines: TextLines<R>,
    opts: ReadOptions,
    stats: ReadStats,
    last_scan_time: f64,
}

/// One record of a log, in file order.
pub enum LogItem {
    Scan(LaserRecord),
    Odom(OdomRecord),
    Param(String, String),
}

impl<R: BufRead> LogReader<R> {
    /// Reads from any reader; `name` is used in error messages.
    pub fn new(reader: R, name: &str, opts: &ReadOptions) -> Self {
        Self {
            lines: TextLines::new(reader, name),
            opts: opts.clone(),
            stats: ReadStats::default(),
            last_scan_time: f64::NEG_INFINITY,
        }
    }

    /// What has been read so far.
    pub fn stats(&self) -> &ReadStats {
        &self.stats
    }

    /// The 1-based line of the record last returned, so later checks can name it.
    pub fn line_no(&self) -> usize {
        self.lines.line_no()
    }

    /// The next scan, odometry or parameter record; `None` at the end of the log.
    pub fn next_item(&mut self) -> Result<Option<LogItem>, ReadError> {
        loop {
            let Some((_, line)) = self.lines.next_line()? else {
                return Ok(None);
            };
            self.stats.lines += 1;
            let stats = &mut self.stats;
            match parse_line(line, &self.opts) {
                Ok(Parsed::Scan(rec, is_flaser)) => {
                    if rec.timestamp_s < self.last_scan_time {
                        stats.non_monotonic_scans += 1;
                    }
                    self.last_scan_time = rec.timestamp_s;
                    *(if is_flaser {
                        &mut stats.flaser
                    } else {
                        &mut stats.robotlaser1
                    }) += 1;
                    return Ok(Some(LogItem::Scan(rec)));
                }
                Ok(Parsed::Odom(o)) => {
                    stats.odom += 1;
                    return Ok(Some(LogItem::Odom(o)));
                }
                Ok(Parsed::Param(k, v)) => {
                    stats.params += 1;
                    return Ok(Some(LogItem::Param(k, v)));
                }
                Ok(Parsed::Comment) => stats.comments += 1,
                Ok(Parsed::Other) => stats.other_records += 1,
                Err(message) if self.opts.skip_bad_lines => {
                    stats.bad_lines += 1;
                    let at = format!("{}:{}: {message}", self.lines.name(), self.lines.line_no());
                    stats.first_bad_line.get_or_insert(at);
                }
                Err(message) => return Err(self.lines.error(message)),
            }
        }
    }

    /// The next scan, passing over the other records; `None` at the end of the log.
    pub fn next_scan(&mut self) -> Result<Option<LaserRecord>, ReadError> {
        loop {
            match self.next_item()? {
                Some(LogItem::Scan(rec)) => return Ok(Some(rec)),
                Some(_) => {}
                None => return Ok(None),
            }
        }
    }
}

/// Opens a log file for reading record by record (gzip by content), with its read progress.
pub fn open_log(
    path: &Path,
    opts: &ReadOptions,
) -> Result<(LogReader<Box<dyn BufRead>>, ReadProgress), ReadError> {
    let input = open_input(path)?;
    Ok((
        LogReader::new(input.reader, &input.name, opts),
        input.progress,
    ))
}

/// Reads a whole log file into memory (gzip by content).
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<CarmenLog, ReadError> {
    let (reader, _) = open_log(path, opts)?;
    collect_log(reader)
}

/// Parses a whole log from any reader; `name` is used in error messages.
pub fn parse_log<R: BufRead>(
    reader: R,
    name: &str,
    opts: &ReadOptions,
) -> Result<CarmenLog, ReadError> {
    collect_log(LogReader::new(reader, name, opts))
}

fn collect_log<R: BufRead>(mut reader: LogReader<R>) -> Result<CarmenLog, ReadError> {
    let mut log = CarmenLog::default();
    while let Some(item) = reader.next_item()? {
        match item {
            LogItem::Scan(rec) => {
                log.scans.push(rec);
                log.scan_lines.push(reader.line_no());
            }
            LogItem::Odom(o) => log.odometry.push(o),
            LogItem::Param(k, v) => log.params.push((k, v)),
        }
    }
    log.stats = reader.stats;
    Ok(log)
}
