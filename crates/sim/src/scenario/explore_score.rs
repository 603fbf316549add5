//! Scoring an exploration against the world's truth: how much of the reachable area was seen
//! and how soon ([`Coverage`]), contacts with walls and people and the closest approach, the
//! way home and the landing, and the companion's map against the true walls.

use super::coverage::Coverage;
use crate::map_error::grid_map_error;
use crate::runner::companion::{CompanionLog, ExploreEnd, Strategy};
use crate::runner::onboard_link::FlightLog;
use crate::runner::{Outcome, SimConfig, StateSample, Status, TruthPose};
use crate::sensors::lidar::LidarScan;
use crate::world::Walker;
use plumbline_core::msgs::FailsafeReason;
use plumbline_explore::Explorer;
use plumbline_slam::grid::OccupancyGrid;

/// The share of the reachable area whose first reaching is reported.
pub const EXPLORED_TARGET: f64 = 0.9;
/// "Back home": the vehicle ended this close to its take-off point, m.
pub const HOME_TOLERANCE_M: f64 = 0.3;

/// How an exploration did (plain figures; the map and the series are in [`Exploration`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ExploreScore {
    pub strategy: Strategy,
    /// Share of the reachable area seen, 0..1.
    pub explored_fraction: f64,
    pub reachable_area_m2: f64,
    /// When [`EXPLORED_TARGET`] of it had been seen, s.
    pub time_to_90pct_s: Option<f64>,
    /// Contacts with walls (a crash ends the run) and with people.
    pub collisions: usize,
    /// Closest approach of the vehicle's centre to a wall (within the runner's 2 m search) or
    /// to a person's body, m.
    pub min_clearance_m: f64,
    /// Distance of the final true position from the take-off point, m.
    pub home_error_m: f64,
    /// Explored, then ended within [`HOME_TOLERANCE_M`] of the take-off point.
    pub returned_home: bool,
    /// It flew, did not crash, and ended disarmed on the ground.
    pub landed: bool,
    /// Mean distance of the companion map's occupied cells from the true walls, m.
    pub map_error_m: Option<f64>,
    /// When and why exploring ended.
    pub explore_end: Option<(f64, ExploreEnd)>,
    pub failsafe: Option<FailsafeReason>,
}

/// What the plots need besides the score: the companion's final map and where its frame lies
/// in the world, the explored fraction over time, the companion's log.
#[derive(Clone, Debug)]
pub struct Exploration {
    pub map: OccupancyGrid,
    /// World pose (x, y, yaw) of the map frame: the true pose at the first scan.
    pub map_in_world: [f64; 3],
    /// (time, explored fraction) after each revolution.
    pub explored: Vec<(f64, f64)>,
    pub companion: CompanionLog,
}

/// What the exploring crew left: the flight part's log, the companion's, its explorer.
pub(super) struct ExploreLogs<'a> {
    pub strategy: Strategy,
    pub log: &'a FlightLog,
    pub companion: CompanionLog,
    pub explorer: &'a Explorer,
    /// The onboard score's verdict on the landing.
    pub landed: bool,
}

/// Watches an exploring flight: the coverage as the scans arrive, the people as the vehicle
/// moves among them.
pub(super) struct ExploreWatch {
    coverage: Coverage,
    walkers: Vec<Walker>,
    /// Centre distances below this are a contact with a person, m.
    contact_m: f64,
    in_contact: bool,
    people_contacts: usize,
    min_people_clearance_m: f64,
    first_scan: Option<[f64; 3]>,
}

impl ExploreWatch {
    pub(super) fn new(config: &SimConfig) -> Self {
        let radius_m = config.vehicle.radius_m;
        Self {
            coverage: Coverage::new(&config.world, radius_m),
            walkers: if config.people {
                config.world.walkers.clone()
            } else {
                Vec::new()
            },
            contact_m: radius_m + Walker::RADIUS_M,
            in_contact: false,
            people_contacts: 0,
            min_people_clearance_m: f64::INFINITY,
            first_scan: None,
        }
    }

    pub(super) fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        let yaw = truth.attitude.yaw();
        let p = truth.position;
        self.first_scan.get_or_insert([p.x, p.y, yaw]);
        self.coverage.observe(scan, p, yaw);
    }

    /// People are met at the state rate (50 Hz: at 0.5 m/s the vehicle moves 1 cm between
    /// looks).
    pub(super) fn state(&mut self, s: &StateSample) {
        let p = s.position;
        let nearest = self
            .walkers
            .iter()
            .map(|w| {
                let q = w.position(s.t_s);
                (p.x - q[0]).hypot(p.y - q[1])
            })
            .fold(f64::INFINITY, f64::min);
        let touching = nearest < self.contact_m && p.z < Walker::HEIGHT_M;
        if touching && !self.in_contact {
            self.people_contacts += 1;
        }
        self.in_contact = touching;
        self.min_people_clearance_m = self.min_people_clearance_m.min(nearest - Walker::RADIUS_M);
    }

    /// The score of the finished flight.
    pub(super) fn score(
        self,
        logs: ExploreLogs<'_>,
        config: &SimConfig,
        outcome: &Outcome,
        states: &[StateSample],
    ) -> (ExploreScore, Exploration) {
        let ExploreLogs {
            strategy,
            log,
            companion,
            explorer,
            landed,
        } = logs;
        let start = config.world.start;
        let map_in_world = self.first_scan.unwrap_or(start);
        let map = explorer.map().grid().clone();
        let map_error_m = grid_map_error(&map, &config.world, map_in_world).map(|e| e.mean_m);
        let home_error_m = states.last().map_or(0.0, |s| {
            (s.position.x - start[0]).hypot(s.position.y - start[1])
        });
        let crashed = matches!(outcome.status, Status::Crashed { .. });
        let explore_end = companion.explore_end;
        let score = ExploreScore {
            strategy,
            explored_fraction: self.coverage.fraction(),
            reachable_area_m2: self.coverage.area_m2(),
            time_to_90pct_s: self.coverage.time_to(EXPLORED_TARGET),
            collisions: usize::from(crashed) + self.people_contacts,
            min_clearance_m: outcome.min_clearance_m.min(self.min_people_clearance_m),
            home_error_m,
            returned_home: explore_end.is_some() && home_error_m <= HOME_TOLERANCE_M,
            landed,
            map_error_m,
            explore_end,
            failsafe: log.failsafe,
        };
        let exploration = Exploration {
            map,
            map_in_world,
            explored: self.coverage.series().to_vec(),
            companion,
        };
        (score, exploration)
    }
}
