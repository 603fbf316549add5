//! A scenario's parts: the catalogue [`Entry`], the plain [`Options`] it is flown with, why it
//! may be refused ([`ScenarioError`]), the prepared [`Flight`], and [`fly`], which runs and
//! scores it.

use super::explore_score::Exploration;
use super::score::{self, Judge, Score};
use super::track::TrackShape;
use crate::disturb::Push;
use crate::runner::companion::{CompanionLog, Strategy};
use crate::runner::crew::AnyExploreCrew;
use crate::runner::ground::GroundStation;
use crate::runner::mission::Mission;
use crate::runner::onboard_link::FlightLog;
use crate::runner::plan::Plan;
use crate::runner::{self, Outcome, Pilot, Recorder, SetupError, SimConfig};
use crate::world::WorldError;
use plumbline_core::matching::local_map::MapCell;
use plumbline_explore::Explorer;
use std::cell::RefCell;
use std::rc::Rc;

/// One scenario of the catalogue.
#[derive(Clone, Copy)]
pub struct Entry {
    pub name: &'static str,
    /// One line for help text.
    pub about: &'static str,
    pub(super) prepare: fn(&Options, &mut SimConfig) -> Result<Flight, ScenarioError>,
}

/// Who flies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Controller {
    /// The onboard cascade of PID loops.
    Pid,
    /// The onboard cascade with model-reference adaptive control (an RBF network with
    /// e-modification and pseudo-control hedging) in place of its position and velocity PIDs.
    Mrac,
    /// The simulator's ground-truth pilot.
    TestPilot,
}

impl Controller {
    pub fn name(self) -> &'static str {
        match self {
            Controller::Pid => "pid",
            Controller::Mrac => "mrac",
            Controller::TestPilot => "test-pilot",
        }
    }
}

/// The onboard PID gains.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tuning {
    /// The defaults.
    #[default]
    Aggressive,
    /// Slower outer loops (seed 000's energy hypothesis compares the two).
    Soft,
}

/// Gains of the onboard position and velocity loops and its command filter, each replacing the
/// tuning's value when set (the energy study sweeps them). Valid ranges: [`GAIN_RANGES`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gains {
    /// Position error (m) -> velocity setpoint (m/s), per horizontal axis, 1/s.
    pub position_kp: Option<f32>,
    /// Velocity error (m/s) -> acceleration (m/s^2), per horizontal axis, 1/s.
    pub velocity_kp: Option<f32>,
    /// Integral of the velocity error (m) -> acceleration (m/s^2), 1/s^2.
    pub velocity_ki: Option<f32>,
    /// Time constant of the low-pass on the tilt command, s (0: none).
    pub command_tau_s: Option<f32>,
}

/// The values [`Gains`] accepts, inclusive: (name, low, high), in field order. Beyond them the
/// cascade is either too sluggish to hold 1 m over the start or oscillates on lidar noise.
pub const GAIN_RANGES: [(&str, f64, f64); 4] = [
    ("position_kp", 0.1, 5.0),
    ("velocity_kp", 0.5, 10.0),
    ("velocity_ki", 0.0, 2.0),
    ("command_tau_s", 0.0, 1.0),
];

impl Gains {
    /// The set values, each checked against [`GAIN_RANGES`].
    pub fn check(&self) -> Result<(), String> {
        let values = [
            self.position_kp,
            self.velocity_kp,
            self.velocity_ki,
            self.command_tau_s,
        ];
        for ((name, lo, hi), v) in GAIN_RANGES.iter().zip(values) {
            if let Some(v) = v.filter(|v| !(*lo..=*hi).contains(&f64::from(*v))) {
                return Err(format!("{name} = {v} is outside [{lo}, {hi}]"));
            }
        }
        Ok(())
    }
}

/// How to fly a scenario; plain values, whatever front end chose them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// `None`: the scenario's own choice (the onboard PID stack, or the test pilot for the
    /// survey).
    pub controller: Option<Controller>,
    pub tuning: Tuning,
    /// Overrides of the tuning's outer-loop gains and command filter.
    pub gains: Gains,
    /// The scan matcher's dynamic-object rejection (seed 000 sec. 4.2).
    pub dynamic_rejection: bool,
    /// Run length, s: the scenario's default when `None`.
    pub duration_s: Option<f64>,
    /// How an exploring vehicle chooses where to go.
    pub strategy: Strategy,
    /// The path of the `track` scenario.
    pub track: TrackShape,
}

impl Default for Options {
    /// The scenario's own controller, default tuning, rejection on, default length.
    fn default() -> Self {
        Self {
            controller: None,
            tuning: Tuning::default(),
            gains: Gains::default(),
            dynamic_rejection: true,
            duration_s: None,
            strategy: Strategy::default(),
            track: TrackShape::default(),
        }
    }
}

/// Why a scenario cannot be flown as asked.
#[derive(Clone, Debug, PartialEq)]
pub enum ScenarioError {
    /// `controller` cannot fly `scenario`; `instead` can (`None`: leave the choice to the
    /// scenario).
    Controller {
        scenario: &'static str,
        controller: Controller,
        reason: &'static str,
        instead: Option<Controller>,
    },
    /// The world does not allow the scenario.
    World(WorldError),
    /// The run cannot be set up (a lidar too large for the onboard stack, for one).
    Setup(SetupError),
}

impl core::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ScenarioError::Controller {
                scenario,
                controller,
                reason,
                instead,
            } => {
                write!(
                    f,
                    "{scenario} with controller {}: {reason}",
                    controller.name()
                )?;
                match instead {
                    Some(c) => write!(f, "; use controller {}", c.name()),
                    None => write!(f, "; leave the controller unset"),
                }
            }
            ScenarioError::World(e) => write!(f, "{e}"),
            ScenarioError::Setup(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ScenarioError {}

/// Who flies: ready, or an exploring crew that boards in [`fly`], which owns the cells its
/// SLAM borrows for the flight.
enum Crew {
    Ready(Pilot<'static>),
    Explore(Box<AnyExploreCrew>),
}

/// A scenario set up and ready to fly.
pub struct Flight {
    crew: Crew,
    judge: Judge,
    /// How long the flight is planned to last, s (for progress).
    pub planned_s: f64,
}

impl Flight {
    /// The test pilot flying `plan`, scored on how closely it follows the plan.
    pub fn test_pilot(plan: Plan, config: &SimConfig) -> Self {
        let planned_s = plan.duration_s().min(config.max_duration_s);
        Self {
            crew: Crew::Ready(Pilot::Test(plan)),
            judge: Judge::Tracking,
            planned_s,
        }
    }

    /// Onboard software that logs into `log`, scored on holding over the start; `push` is the
    /// scenario's own push, whose effect is scored apart; the `mission` it flies, if any, is
    /// scored on tracking.
    pub fn onboard(
        pilot: Pilot<'static>,
        log: Rc<RefCell<FlightLog>>,
        push: Option<Push>,
        mission: Option<Mission>,
        config: &SimConfig,
    ) -> Self {
        Self {
            crew: Crew::Ready(pilot),
            judge: Judge::Onboard { log, push, mission },
            planned_s: config.max_duration_s,
        }
    }

    /// The onboard stack exploring with its companion, scored on the exploration; `log` is
    /// the stack's, `companion` and `explorer` the companion's.
    pub fn explore(
        crew: AnyExploreCrew,
        strategy: Strategy,
        log: Rc<RefCell<FlightLog>>,
        companion: Rc<RefCell<CompanionLog>>,
        explorer: Rc<RefCell<Explorer>>,
        config: &SimConfig,
    ) -> Self {
        Self {
            crew: Crew::Explore(Box::new(crew)),
            judge: Judge::Explore {
                strategy,
                log,
                companion,
                explorer,
            },
            planned_s: config.max_duration_s,
        }
    }
}

impl Flight {
    /// Links a ground station to the onboard stack; the test pilot has no ground link and
    /// hands it back.
    pub fn link_ground(
        &mut self,
        station: Box<dyn GroundStation>,
    ) -> Result<(), Box<dyn GroundStation>> {
        match &mut self.crew {
            Crew::Ready(Pilot::Onboard(software)) => software.link_ground(station),
            Crew::Ready(Pilot::Test(_)) => Err(station),
            Crew::Explore(crew) => {
                crew.link_ground(station);
                Ok(())
            }
        }
    }
}

impl Entry {
    /// Sets the scenario up on `config` (which it may change: duration, pushes, battery,
    /// people) and checks the result: the world's survey path free for the vehicle, and
    /// everything the runner needs ([`SimConfig::validate`]). A flight that is returned
    /// starts; nothing is refused after this, so callers may create their output files.
    pub fn prepare(
        &self,
        options: &Options,
        config: &mut SimConfig,
    ) -> Result<Flight, ScenarioError> {
        let flight = (self.prepare)(options, config)?;
        for p in &config.world.path {
            config
                .world
                .check_free(*p, config.vehicle.radius_m, "survey waypoint")
                .map_err(ScenarioError::World)?;
        }
        config.validate().map_err(ScenarioError::Setup)?;
        Ok(flight)
    }
}

/// What a flight did: the runner's figures, the score, the onboard stack's own log when it
/// flew, and the companion's map and coverage series when it explored.
#[derive(Clone, Debug)]
pub struct Report {
    pub outcome: Outcome,
    pub score: Score,
    pub onboard: Option<FlightLog>,
    pub exploration: Option<Exploration>,
}

/// Flies `flight` on `config` (as prepared for it), handing every sample to `recorder`, and
/// scores it.
pub fn fly(
    config: &SimConfig,
    flight: Flight,
    recorder: &mut dyn Recorder,
) -> Result<Report, SetupError> {
    let mut scorer = score::Scorer::new(recorder, &flight.judge, config);
    // The SLAM's local map of an exploring crew: here, so that it outlives the flight.
    let mut cells: Vec<MapCell>;
    let pilot = match flight.crew {
        Crew::Ready(pilot) => pilot,
        Crew::Explore(crew) => {
            cells = crew.local_map();
            crew.board(&mut cells)?
        }
    };
    let outcome = runner::run(config, pilot, &mut scorer)?;
    let (score, onboard, exploration) = scorer.score(flight.judge, config, &outcome);
    Ok(Report {
        outcome,
        score,
        onboard,
        exploration,
    })
}
