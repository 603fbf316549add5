//! `explore`: the vehicle explores a building it has never seen and comes home. The onboard
//! stack takes off and holds; its companion computer (online SLAM, the explorer's live map and
//! frontiers, seed 002's velocity field; `runner::companion`) sends it the SLAM pose and the
//! setpoints of the exploration, then of the way home, and the autopilot lands at the
//! take-off point. Lockstep and inline, so a run is a function of its seed.
//!
//! Scored against the world's truth ([`super::explore_score`]): the share of the reachable area
//! seen and how soon, contacts and the closest approach, the way home, the landing, the map.
//! The world's people walk unless the caller leaves them out.

use super::flight::{Entry, Flight, Options, ScenarioError};
use super::onboard::{self, ARM_AT_S};
use crate::runner::companion::CompanionLog;
use crate::runner::crew::{AnyExploreCrew, CompanionParts, ExploreCrew};
use crate::runner::onboard_link::{FlightLog, OnboardLink, Script, LARGE_SCAN_BEAMS, XV11_BEAMS};
use crate::runner::{SetupError, SimConfig};
use plumbline_core::guidance::config::GuidanceConfig;
use plumbline_core::guidance::ApproachLimit;
use plumbline_explore::{ExploreConfig, Explorer};
use plumbline_slam::SlamConfig;
use std::cell::RefCell;
use std::rc::Rc;

pub(super) const ENTRY: Entry = Entry {
    name: "explore",
    about: "explore the world from the start on the SLAM map, come home and land",
    prepare,
};

/// Run length when the options give none, s: ten minutes, the time a building is to be
/// explored in.
const DEFAULT_DURATION_S: f64 = 600.0;

fn prepare(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    let people = config.people;
    onboard::setup(ENTRY.name, options, config)?;
    config.people = people;
    config.max_duration_s = options.duration_s.unwrap_or(DEFAULT_DURATION_S);
    let radius_m = config.vehicle.radius_m as f32;
    let guidance = GuidanceConfig {
        vehicle_radius_m: radius_m,
        ..GuidanceConfig::default()
    };
    let explore_config = ExploreConfig {
        vehicle_radius_m: radius_m,
        preferred_clearance_m: guidance.r_min_m(),
        ..ExploreConfig::default()
    };
    let setup = |e: String| ScenarioError::Setup(SetupError::Config(e));
    guidance.validate().map_err(|e| setup(e.to_string()))?;
    let explorer = Rc::new(RefCell::new(
        Explorer::new(explore_config).map_err(|e| setup(e.to_string()))?,
    ));
    let companion = Rc::new(RefCell::new(CompanionLog::default()));
    let parts = CompanionParts {
        slam: SlamConfig::in_flight(),
        explorer: explorer.clone(),
        guidance,
        strategy: options.strategy,
        turns: config.lidar.beams as f64 * config.lidar.increment_rad.abs()
            < std::f64::consts::TAU - 1e-6,
        end_s: config.max_duration_s,
        log: companion.clone(),
    };
    let (crew, log) = if config.lidar.beams <= XV11_BEAMS {
        let (crew, log) = crew::<XV11_BEAMS>(options, config, parts)?;
        (AnyExploreCrew::Small(crew), log)
    } else {
        let (crew, log) = crew::<LARGE_SCAN_BEAMS>(options, config, parts)?;
        (AnyExploreCrew::Large(crew), log)
    };
    Ok(Flight::explore(
        crew,
        options.strategy,
        log,
        companion,
        explorer,
        config,
    ))
}

/// The onboard stack for scans of up to `N` beams, armed by the pilot, with the companion.
fn crew<const N: usize>(
    options: &Options,
    config: &SimConfig,
    companion: CompanionParts,
) -> Result<(ExploreCrew<N>, Rc<RefCell<FlightLog>>), ScenarioError> {
    let (odometry, mut autopilot) = onboard::stack(options, config)?;
    // The flight part guards what it flies by the guidance's own rule.
    autopilot.mission.guard = ApproachLimit::from(&companion.guidance);
    let script = Script::arm_at(ARM_AT_S);
    let (link, log) = OnboardLink::<N>::new(&config.lidar, odometry, autopilot, script)
        .map_err(ScenarioError::Setup)?;
    Ok((ExploreCrew { link, companion }, log))
}
