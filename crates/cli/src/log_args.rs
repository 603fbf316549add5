//! Options shared by every subcommand that reads a CARMEN log.

use crate::numeric::{within, Range};
use crate::report::CliError;
use clap::Args;
use plumbline_core::geom::Pose2;
use plumbline_io::carmen::{
    read_log, CarmenLog, FovRule, OdomPose, ReadOptions, ReadStats, FLASER_MAX_RANGE_M,
};
use std::path::Path;

#[derive(Args, Debug, Clone)]
pub struct LogArgs {
    /// Field of view of FLASER scans in degrees (FLASER does not store it). Default: the
    /// benchmark convention, 180 degrees (180/181 beams at 1 degree, 360/361 at 0.5 degree).
    /// Valid range: (0, 360].
    #[arg(long, value_name = "DEG", value_parser = within::<f32>(Range::above(0.0, 360.0)))]
    pub fov_deg: Option<f32>,
    /// FLASER readings at or above this are "no return" (SICK's 81.83/81.91 m sentinels).
    /// Valid range: (0, 1000].
    #[arg(long, value_name = "M", default_value_t = FLASER_MAX_RANGE_M,
          value_parser = within::<f32>(Range::above(0.0, 1000.0)))]
    pub max_range: f32,
    /// Count and pass over malformed lines instead of stopping at the first one.
    #[arg(long)]
    pub skip_bad_lines: bool,
}

impl LogArgs {
    /// The reader options; their values were checked while the command line was read.
    pub fn options(&self) -> ReadOptions {
        let fov = match self.fov_deg {
            None => FovRule::Conventional,
            Some(d) => FovRule::Radians(d.to_radians()),
        };
        ReadOptions {
            fov,
            flaser_max_range_m: self.max_range,
            skip_bad_lines: self.skip_bad_lines,
        }
    }

    /// Reads a whole log into memory, for commands that need all of it at once.
    pub fn read(&self, path: &Path) -> Result<CarmenLog, CliError> {
        let log = read_log(path, &self.options())?;
        report_bad_lines(&log.stats);
        if log.scans.is_empty() {
            return Err(no_scans(path));
        }
        Ok(log)
    }
}

/// Says how many malformed lines `--skip-bad-lines` passed over, and the first of them.
pub fn report_bad_lines(stats: &ReadStats) {
    if stats.bad_lines > 0 {
        eprintln!(
            "plumbline: passed over {} malformed line(s); first: {}",
            stats.bad_lines,
            stats.first_bad_line.as_deref().unwrap_or("?")
        );
    }
}

/// The error for a log without one scan.
pub fn no_scans(path: &Path) -> CliError {
    CliError(format!(
        "{}: no FLASER or ROBOTLASER1 scans in the log",
        path.display()
    ))
}

/// The log's own odometry between two scans as the matcher's motion guess: only when the user
/// asked for it and both scans carry a pose.
pub fn odometry_prior(
    enabled: bool,
    previous: Option<OdomPose>,
    current: Option<OdomPose>,
) -> Option<Pose2> {
    match (enabled, previous, current) {
        (true, Some(a), Some(b)) => Some(a.between(b).to_f32()),
        _ => None,
    }
}
