//! One revolution through the companion: the autopilot's estimated motion since the previous
//! revolution as the SLAM's motion guess, SLAM, the pose fix, the obstacles around, and what
//! goes to the autopilot, with the counts and times the summary reports.
//!
//! The guess follows the simulator's rule ([`EstimatedMotion`]): none for the first revolution,
//! none while the autopilot's estimate is missing, stale, unusable or broken
//! ([`Withheld`]), and none for the revolution after, so a guess never spans a gap. Without one
//! the SLAM guesses from the lidar alone (the last motion carried on), as it did before the
//! autopilot was heard: a run is never stopped or refused for want of an estimate.

use super::fix::{FixMaker, Resets};
use crate::odometry_cmd::{percentile, MAX_BEAMS};
use crate::report::CliError;
use plumbline_core::msgs::{EstimatedState, PoseFix};
use plumbline_core::scan::{Beam, Scan};
use plumbline_io::carmen::LaserRecord;
use plumbline_link::Withheld;
use plumbline_slam::{EstimatedMotion, Slam};
use serde_json::{json, Value};
use std::time::Instant;

/// Seconds between heartbeats, on the scans' clock (the host's for a live lidar).
const HEARTBEAT_PERIOD_S: f64 = 1.0;

/// What the companion tells the autopilot; the MAVLink encoding lives behind it.
pub trait AutopilotLink {
    /// HEARTBEAT: a companion computer is here.
    fn heartbeat(&mut self, t_s: f64) -> Result<bool, CliError>;
    /// ODOMETRY from a pose fix.
    fn odometry(&mut self, fix: &PoseFix) -> Result<bool, CliError>;
    /// OBSTACLE_DISTANCE from a revolution's beams (body frame); `max_range_m` is the lidar's
    /// reach.
    fn obstacles(&mut self, t_s: f64, beams: &[Beam], max_range_m: f32) -> Result<bool, CliError>;
    /// The autopilot's estimate now (ENU), or why there is none.
    fn estimate(&mut self) -> Result<EstimatedState, Withheld>;
}

/// A link lent to a run, so the caller reads its counters afterwards.
impl<T: AutopilotLink> AutopilotLink for &mut T {
    fn heartbeat(&mut self, t_s: f64) -> Result<bool, CliError> {
        (**self).heartbeat(t_s)
    }
    fn odometry(&mut self, fix: &PoseFix) -> Result<bool, CliError> {
        (**self).odometry(fix)
    }
    fn obstacles(&mut self, t_s: f64, beams: &[Beam], max_range_m: f32) -> Result<bool, CliError> {
        (**self).obstacles(t_s, beams, max_range_m)
    }
    fn estimate(&mut self) -> Result<EstimatedState, Withheld> {
        (**self).estimate()
    }
}

/// Messages handed to the link: sent, or dropped because they could not go out at once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counted {
    pub sent: usize,
    pub dropped: usize,
}

impl Counted {
    fn add(&mut self, sent: bool) {
        if sent {
            self.sent += 1;
        } else {
            self.dropped += 1;
        }
    }
}

/// Revolutions whose motion guess came from the autopilot, and why the others had none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Guesses {
    pub guessed: usize,
    pub missing: usize,
    pub stale: usize,
    pub invalid: usize,
    pub discontinuities: usize,
}

impl Guesses {
    fn count(&mut self, reading: &Result<EstimatedState, Withheld>, guessed: bool) {
        self.guessed += usize::from(guessed);
        if let Err(why) = reading {
            *match why {
                Withheld::Missing => &mut self.missing,
                Withheld::Stale => &mut self.stale,
                Withheld::Invalid => &mut self.invalid,
                Withheld::Discontinuity => &mut self.discontinuities,
            } += 1;
        }
    }
}

/// The SLAM and the link, and what the run has seen so far.
pub struct Companion<'m, L> {
    slam: Slam<'m, MAX_BEAMS>,
    fixes: FixMaker,
    link: L,
    motion: EstimatedMotion,
    pub guesses: Guesses,
    scan: Box<Scan<MAX_BEAMS>>,
    last_heartbeat_s: Option<f64>,
    previous_s: Option<f64>,
    pub scans: usize,
    /// Revolutions with no valid beam (a covered or stopped lidar).
    pub empty_scans: usize,
    /// Revolutions whose match failed (sent with quality -1).
    pub lost_scans: usize,
    /// Time between revolutions whose pose was a prediction, summed (s).
    pub lost_s: f64,
    pub odometry: Counted,
    pub obstacles: Counted,
    pub heartbeats: Counted,
    /// Every revolution's time through the pipeline (µs): SLAM, fix, encoding, sending.
    times_us: Vec<f64>,
    /// The last fix sent, for tests and the summary.
    pub last_fix: Option<PoseFix>,
}

impl<'m, L: AutopilotLink> Companion<'m, L> {
    pub fn new(slam: Slam<'m, MAX_BEAMS>, link: L) -> Self {
        Self {
            slam,
            fixes: FixMaker::default(),
            link,
            motion: EstimatedMotion::default(),
            guesses: Guesses::default(),
            scan: Box::default(),
            last_heartbeat_s: None,
            previous_s: None,
            scans: 0,
            empty_scans: 0,
            lost_scans: 0,
            lost_s: 0.0,
            odometry: Counted::default(),
            obstacles: Counted::default(),
            heartbeats: Counted::default(),
            times_us: Vec::new(),
            last_fix: None,
        }
    }

    /// One revolution: an error only for what ends the run (a scan larger than any lidar's,
    /// the autopilot's port gone); everything else is counted and reported.
    pub fn revolution(&mut self, rec: &LaserRecord) -> Result<(), CliError> {
        let t_s = rec.timestamp_s;
        // A clock that steps back (a device reset) restarts the heartbeat period too.
        if self
            .last_heartbeat_s
            .is_none_or(|h| t_s - h >= HEARTBEAT_PERIOD_S || t_s < h)
        {
            let s = self.link.heartbeat(t_s)?;
            self.heartbeats.add(s);
            self.last_heartbeat_s = Some(t_s);
        }
        *self.scan = rec.to_scan().map_err(|_| {
            CliError(format!(
                "revolution {} has {} beams; at most {MAX_BEAMS} are supported",
                self.scans + 1,
                rec.beam_count()
            ))
        })?;
        self.scans += 1;
        self.empty_scans += usize::from(self.scan.valid_count() == 0);
        let start = Instant::now();
        let reading = self.link.estimate();
        let prior = self
            .motion
            .since_last(reading.as_ref().unwrap_or(&EstimatedState::default()));
        self.guesses.count(&reading, prior.is_some());
        let at = self.slam.add_scan(&self.scan, prior);
        let fix = self.fixes.fix(&self.slam, t_s, &at);
        let sent = self.link.odometry(&fix)?;
        self.odometry.add(sent);
        let sent = self
            .link
            .obstacles(t_s, self.scan.beams(), rec.max_range_m)?;
        self.obstacles.add(sent);
        self.times_us.push(start.elapsed().as_secs_f64() * 1e6);
        if at.predicted {
            self.lost_scans += 1;
            self.lost_s += self.previous_s.map_or(0.0, |p| (t_s - p).abs());
        }
        self.previous_s = Some(t_s);
        self.last_fix = Some(fix);
        Ok(())
    }

    /// The revolution just sent, in the body frame.
    pub fn beams(&self) -> &[Beam] {
        self.scan.beams()
    }

    pub fn resets(&self) -> Resets {
        self.fixes.resets
    }

    /// The summary keys of the pipeline itself.
    pub fn summary(&self) -> Value {
        let mut times = self.times_us.clone();
        times.sort_by(f64::total_cmp);
        let resets = self.resets();
        json!({
            "scans": self.scans,
            "empty_scans": self.empty_scans,
            "lost_scans": self.lost_scans,
            "lost_s": self.lost_s,
            "relocalizations": resets.total(),
            "map_corrections": resets.map_corrections,
            "recoveries": resets.recoveries,
            "wide_searches": resets.searches,
            "reset_counter": self.last_fix.map(|f| f.reset_counter),
            "odometry_sent": self.odometry.sent,
            "odometry_dropped": self.odometry.dropped,
            "obstacle_distance_sent": self.obstacles.sent,
            "obstacle_distance_dropped": self.obstacles.dropped,
            "heartbeats_sent": self.heartbeats.sent,
            "motion_guesses": self.guesses.guessed,
            "estimate_missing": self.guesses.missing,
            "estimate_stale": self.guesses.stale,
            "estimate_invalid": self.guesses.invalid,
            "estimate_discontinuities": self.guesses.discontinuities,
            "median_scan_us": percentile(&times, 0.5),
            "p99_scan_us": percentile(&times, 0.99),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_slam::{local_map_cells, SlamConfig};

    /// A link that sends everything and answers with scripted estimates, one per revolution.
    struct Scripted(std::vec::IntoIter<Result<EstimatedState, Withheld>>);

    impl AutopilotLink for Scripted {
        fn heartbeat(&mut self, _: f64) -> Result<bool, CliError> {
            Ok(true)
        }
        fn odometry(&mut self, _: &PoseFix) -> Result<bool, CliError> {
            Ok(true)
        }
        fn obstacles(&mut self, _: f64, _: &[Beam], _: f32) -> Result<bool, CliError> {
            Ok(true)
        }
        fn estimate(&mut self) -> Result<EstimatedState, Withheld> {
            self.0.next().unwrap()
        }
    }

    /// A revolution in a 4 m by 6 m room, centred, facing +x.
    fn room(t_s: f64) -> LaserRecord {
        let n = 360;
        let inc = std::f32::consts::TAU / n as f32;
        let ranges = (0..n)
            .map(|i| {
                let (s, c) = (inc * i as f32 - std::f32::consts::PI).sin_cos();
                // Along an axis one of the two is infinite, and the other wall is nearer.
                (2.0 / c.abs()).min(3.0 / s.abs())
            })
            .collect();
        LaserRecord::new(t_s, -std::f32::consts::PI, inc, 10.0, ranges)
    }

    #[test]
    fn a_guess_needs_two_usable_estimates_in_a_row_and_each_withholding_is_counted() {
        let at = |x: f32| {
            Ok(EstimatedState {
                position_m: [x, 0.0, 1.0],
                valid: true,
                ..EstimatedState::default()
            })
        };
        let script = vec![
            Err(Withheld::Missing),
            at(0.0),
            at(0.0),
            Err(Withheld::Stale),
            at(0.0),
            at(0.0),
            Err(Withheld::Invalid),
            Err(Withheld::Discontinuity),
            at(0.0),
            at(0.0),
        ];
        let config = SlamConfig::in_flight();
        let mut cells = local_map_cells(&config);
        let slam = Slam::new(config, &mut cells, false).unwrap();
        let mut companion = Companion::new(slam, Scripted(script.into_iter()));
        for k in 0..10 {
            companion.revolution(&room(f64::from(k) * 0.2)).unwrap();
        }
        assert_eq!(
            companion.guesses,
            Guesses {
                guessed: 3,
                missing: 1,
                stale: 1,
                invalid: 1,
                discontinuities: 1,
            }
        );
        let s = companion.summary();
        assert_eq!(s["motion_guesses"], 3);
        assert_eq!(s["estimate_discontinuities"], 1);
        assert_eq!(companion.lost_scans, 0);
    }
}
