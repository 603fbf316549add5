//! Scoring a flight against ground truth, in one place: the hold error (DESIGN.md §6: the
//! horizontal distance between the true position and where the vehicle should be), how far a
//! push carried the vehicle and how soon it was back, the estimate's drift, the landing.
//!
//! The test pilot is scored on following its plan, sampled at each of its steps; the onboard
//! stack on holding over the start, from the truth sampled at [`STATE_RATE_HZ`] while its own
//! log says it was in Hold, and on a mission on the tracking error: the horizontal distance
//! between the true position and the mission's setpoint at the same instant, over the
//! mission (the hold error leaves the mission and its settling out).
//!
//! [`STATE_RATE_HZ`]: crate::runner::STATE_RATE_HZ

use super::explore_score::{Exploration, ExploreLogs, ExploreScore, ExploreWatch};
use crate::disturb::Push;
use crate::math::Vec3;
use crate::runner::companion::{CompanionLog, Strategy};
use crate::runner::mission::Mission;
use crate::runner::onboard_link::FlightLog;
use crate::runner::{Outcome, Recorder, SimConfig, StateSample, Status, TruthPose};
use crate::scenario::track::to_world;
use crate::sensors::lidar::LidarScan;
use plumbline_core::msgs::{FlightMode, ImuSample, SonarSample};
use plumbline_explore::Explorer;
use std::cell::RefCell;
use std::rc::Rc;

/// The test pilot is scored while its reference is this high: on the ground and in the first
/// centimetres of the climb it is not tracking anything, m.
const AIRBORNE_M: f64 = 0.3;
/// Hold error is scored from this long after Hold is entered: the end of the climb is a
/// transient, not station keeping, s.
pub const SETTLE_S: f64 = 2.0;
/// Time after a push that is left out of the hold error (seed 000's recovery target); the
/// push itself is scored by [`OnboardScore::push_max_error_m`] and
/// [`OnboardScore::recovery_s`], s.
const RECOVERY_ALLOWANCE_S: f64 = 3.0;
/// "Back on station": within this distance of the hold point, m.
const RECOVERED_M: f64 = 0.05;

/// Horizontal distance of `position` from `target`, m: the one definition of hold error.
pub fn horizontal_error(position: Vec3, target: [f64; 2]) -> f64 {
    (position.x - target[0]).hypot(position.y - target[1])
}

/// RMS and largest of a set of hold errors, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldError {
    pub rms_m: f64,
    pub max_m: f64,
}

/// Hold errors summed as they come.
#[derive(Clone, Copy, Debug, Default)]
pub struct ErrorTally {
    sum_sq: f64,
    count: u64,
    max_m: f64,
}

impl ErrorTally {
    pub fn add(&mut self, error_m: f64) {
        self.sum_sq += error_m * error_m;
        self.count += 1;
        self.max_m = self.max_m.max(error_m);
    }

    /// `None` when nothing was added.
    pub fn result(&self) -> Option<HoldError> {
        (self.count > 0).then(|| HoldError {
            rms_m: (self.sum_sq / self.count as f64).sqrt(),
            max_m: self.max_m,
        })
    }
}

/// The hold error of the true `states` from `point` over the instants `during` accepts.
pub fn hold_error(
    states: &[StateSample],
    point: [f64; 2],
    during: impl Fn(f64) -> bool,
) -> Option<HoldError> {
    let mut tally = ErrorTally::default();
    for s in states.iter().filter(|s| during(s.t_s)) {
        tally.add(horizontal_error(s.position, point));
    }
    tally.result()
}

/// How a flight did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Score {
    /// From the plan's reference (test pilot) or the hold point (onboard); `None` when the
    /// vehicle never held.
    pub hold: Option<HoldError>,
    /// Distance between the onboard estimate and the truth at the end, m (onboard only).
    pub estimate_drift_m: Option<f64>,
    /// From the mission's setpoints while it lasted (onboard flights with a mission only).
    pub track: Option<HoldError>,
    /// The tracking error split in two over the same instants as `track` (onboard flights
    /// with a mission only).
    pub track_parts: Option<TrackParts>,
    pub onboard: Option<OnboardScore>,
    pub explore: Option<ExploreScore>,
}

/// The true tracking error is the estimate's error from the setpoint, which the controller
/// sees and acts on, plus the estimate's error from the truth, which it cannot see.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackParts {
    /// Horizontal distance of the onboard estimate from the setpoint, m.
    pub control: HoldError,
    /// Horizontal distance of the onboard estimate from the truth, m.
    pub estimate: HoldError,
}

/// What only an onboard flight is scored on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OnboardScore {
    /// Largest hold error from the scenario's push until `RECOVERY_ALLOWANCE_S` (3 s) after it, m.
    pub push_max_error_m: Option<f64>,
    /// From the end of the push until back within `RECOVERED_M` (5 cm), s.
    pub recovery_s: Option<f64>,
    /// It flew, did not crash, and ended disarmed on the ground.
    pub landed: bool,
}

/// How a scenario's flight is to be scored.
pub(super) enum Judge {
    /// The test pilot: against its plan.
    Tracking,
    /// The onboard stack, logging into `log`: holding over the start; `push` is the
    /// scenario's own push; `mission` the path it was sent, if any.
    Onboard {
        log: Rc<RefCell<FlightLog>>,
        push: Option<Push>,
        mission: Option<Mission>,
    },
    /// The onboard stack with its exploring companion: scored on what it saw, how safely,
    /// and how it came home.
    Explore {
        strategy: Strategy,
        log: Rc<RefCell<FlightLog>>,
        companion: Rc<RefCell<CompanionLog>>,
        explorer: Rc<RefCell<Explorer>>,
    },
}

/// The one owner's value of a log the runner shared with the flight software (dropped by
/// now, so normally the log is the caller's alone).
fn unshare<T: Clone>(shared: Rc<RefCell<T>>) -> T {
    Rc::try_unwrap(shared)
        .map(RefCell::into_inner)
        .unwrap_or_else(|shared| shared.borrow().clone())
}

/// Passes every sample on to the caller's recorder and keeps what the score needs.
pub(super) struct Scorer<'r> {
    inner: &'r mut dyn Recorder,
    tracking: ErrorTally,
    states: Vec<StateSample>,
    explore: Option<ExploreWatch>,
}

impl<'r> Scorer<'r> {
    pub(super) fn new(inner: &'r mut dyn Recorder, judge: &Judge, config: &SimConfig) -> Self {
        Self {
            inner,
            tracking: ErrorTally::default(),
            states: Vec::new(),
            explore: matches!(judge, Judge::Explore { .. }).then(|| ExploreWatch::new(config)),
        }
    }

    /// The score of the finished run, the onboard stack's log when it flew, and what an
    /// exploration left.
    pub(super) fn score(
        self,
        judge: Judge,
        config: &SimConfig,
        outcome: &Outcome,
    ) -> (Score, Option<FlightLog>, Option<Exploration>) {
        match judge {
            Judge::Tracking => {
                let score = Score {
                    hold: self.tracking.result(),
                    ..Score::default()
                };
                (score, None, None)
            }
            Judge::Onboard { log, push, mission } => {
                let log = unshare(log);
                let score =
                    score_onboard(&log, push, mission.as_ref(), config, outcome, &self.states);
                (score, Some(log), None)
            }
            Judge::Explore {
                strategy,
                log,
                companion,
                explorer,
            } => {
                let log = unshare(log);
                let mut score = score_onboard(&log, None, None, config, outcome, &self.states);
                let watch = self.explore.unwrap_or_else(|| ExploreWatch::new(config));
                let logs = ExploreLogs {
                    strategy,
                    log: &log,
                    companion: unshare(companion),
                    explorer: &explorer.borrow(),
                    landed: score.onboard.is_some_and(|o| o.landed),
                };
                let (explore, exploration) = watch.score(logs, config, outcome, &self.states);
                score.explore = Some(explore);
                (score, Some(log), Some(exploration))
            }
        }
    }
}

impl Recorder for Scorer<'_> {
    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        if let Some(w) = self.explore.as_mut() {
            w.scan(scan, truth);
        }
        self.inner.scan(scan, truth);
    }
    fn imu(&mut self, sample: &ImuSample) {
        self.inner.imu(sample);
    }
    fn sonar(&mut self, sample: &SonarSample) {
        self.inner.sonar(sample);
    }
    fn state(&mut self, sample: &StateSample) {
        if let Some(w) = self.explore.as_mut() {
            w.state(sample);
        }
        self.states.push(*sample);
        self.inner.state(sample);
    }
    fn tracking(&mut self, t_s: f64, position: Vec3, reference: Vec3) {
        if reference.z > AIRBORNE_M {
            self.tracking
                .add(horizontal_error(position, [reference.x, reference.y]));
        }
        self.inner.tracking(t_s, position, reference);
    }
}

/// The time windows in which the vehicle held on station: Hold mode after [`SETTLE_S`].
fn hold_windows(log: &FlightLog, end_s: f64) -> Vec<(f64, f64)> {
    let mut windows = Vec::new();
    for (k, (t, mode)) in log.modes.iter().enumerate() {
        if *mode == FlightMode::Hold {
            let until = log.modes.get(k + 1).map_or(end_s, |m| m.0);
            windows.push((t + SETTLE_S, until));
        }
    }
    windows
}

/// Whether `t` falls in a push of `config` or its recovery allowance.
fn recovering(config: &SimConfig, t: f64) -> bool {
    config
        .pushes
        .iter()
        .any(|p| t >= p.start_s && t < p.start_s + p.duration_s + RECOVERY_ALLOWANCE_S)
}

/// The tracking error of the true `states` from `mission`'s setpoints (estimate frame, which
/// starts at the take-off pose) while it lasted, `shift_s` later than planned; and the error of
/// the onboard estimate (the log's sample nearest in time) from the setpoint and the truth.
fn track_error(
    mission: &Mission,
    shift_s: f64,
    config: &SimConfig,
    log: &FlightLog,
    states: &[StateSample],
) -> (Option<HoldError>, Option<TrackParts>) {
    let mut track = ErrorTally::default();
    let mut control = ErrorTally::default();
    let mut estimate = ErrorTally::default();
    let samples = &log.samples;
    for s in states {
        if let Some((p, _)) = mission.at(s.t_s - shift_s) {
            let start = config.world.start;
            let setpoint = to_world(start, p);
            track.add(horizontal_error(s.position, setpoint));
            let k = samples.partition_point(|o| o.t_s < s.t_s);
            let nearest = [k.checked_sub(1), Some(k)]
                .into_iter()
                .flatten()
                .filter_map(|i| samples.get(i))
                .min_by(|a, b| (a.t_s - s.t_s).abs().total_cmp(&(b.t_s - s.t_s).abs()));
            if let Some(o) = nearest {
                let [ex, ey, _] = o.estimate.position_m.map(f64::from);
                let [wx, wy] = to_world(start, [ex, ey]);
                control.add((wx - setpoint[0]).hypot(wy - setpoint[1]));
                estimate.add(horizontal_error(s.position, [wx, wy]));
            }
        }
    }
    let parts = control
        .result()
        .zip(estimate.result())
        .map(|(control, estimate)| TrackParts { control, estimate });
    (track.result(), parts)
}

/// Scores an onboard flight on the truth `states`: holding over the start outside the pushes
/// (and their recovery), the scenario's `push`, drift of the estimate, landing.
fn score_onboard(
    log: &FlightLog,
    push: Option<Push>,
    mission: Option<&Mission>,
    config: &SimConfig,
    outcome: &Outcome,
    states: &[StateSample],
) -> Score {
    let start = [config.world.start[0], config.world.start[1]];
    let end_s = states.last().map_or(0.0, |s| s.t_s);
    let windows = hold_windows(log, end_s);
    // A mission's path (as late as it started) and its settling are tracking, not station
    // keeping.
    let shift = log.mission_shift_s.unwrap_or(0.0);
    let flying_mission = |t: f64| {
        mission.is_some_and(|m| t >= m.start_s() + shift && t < m.end_s() + shift + SETTLE_S)
    };
    let holding = |t: f64| {
        windows.iter().any(|w| t >= w.0 && t < w.1) && !recovering(config, t) && !flying_mission(t)
    };
    let hold = hold_error(states, start, holding);
    // The scenario's push: how far it carried the vehicle and how soon it was back.
    let pushed = push.filter(|p| config.pushes.contains(p) && end_s > p.start_s + p.duration_s);
    let (push_max_error_m, recovery_s) = match pushed {
        Some(p) => {
            let push_end = p.start_s + p.duration_s;
            let during = |t: f64| t >= p.start_s && t < push_end + RECOVERY_ALLOWANCE_S;
            let max = hold_error(states, start, during).map(|e| e.max_m);
            let recovery = states
                .iter()
                .filter(|s| s.t_s >= push_end)
                .find(|s| horizontal_error(s.position, start) <= RECOVERED_M)
                .map(|s| s.t_s - push_end);
            (max, recovery)
        }
        None => (None, None),
    };
    // The estimate frame starts at the take-off pose.
    let drift = states.last().map(|s| {
        let [ex, ey, _] = log.last_estimate.position_m.map(f64::from);
        horizontal_error(s.position, to_world(config.world.start, [ex, ey]))
    });
    let crashed = matches!(outcome.status, Status::Crashed { .. });
    let flew = log.modes.iter().any(|m| m.1 == FlightMode::Takeoff);
    let (track, track_parts) = mission
        .zip(log.mission_shift_s)
        .map_or((None, None), |(m, shift)| {
            track_error(m, shift, config, log, states)
        });
    Score {
        hold,
        estimate_drift_m: drift,
        track,
        track_parts,
        onboard: Some(OnboardScore {
            push_max_error_m,
            recovery_s,
            landed: !crashed && flew && log.final_mode() == FlightMode::Disarmed,
        }),
        explore: None,
    }
}
