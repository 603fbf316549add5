//! One CARMEN line parsed into a record, with errors that name the field.

use super::read::{OdomRecord, ReadOptions, FLASER_MAX_RANGE_M};
use super::{LaserRecord, OdomPose};

pub(super) enum Parsed {
    Scan(LaserRecord, bool),
    Odom(OdomRecord),
    Param(String, String),
    Comment,
    Other,
}

pub(super) fn parse_line(line: &str, opts: &ReadOptions) -> Result<Parsed, String> {
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
