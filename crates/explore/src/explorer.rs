//! Frontier exploration: where to fly next, when exploring is done, and the way home.
//!
//! Each plan takes the live map in planning cells, grows the obstacles by `r_min`, finds the
//! frontier clusters big enough to matter, and runs Dijkstra from the vehicle over the safe
//! cells to the nearest frontier cell of such a cluster: the nearest reachable frontier by
//! path length, not by straight-line distance. The velocity field flies a waypoint a lookahead
//! distance along that path. A plan is renewed when the goal is reached or seen (its cell is no
//! longer a frontier), when the map changed and the plan is older than the replanning interval,
//! or when the goal has been pursued too long (it is then given up as unreachable).

use crate::config::{ConfigError, ExploreConfig};
use crate::frontier::{clusters, NO_CLUSTER};
use crate::live_map::{LiveMap, MapUpdate};
use crate::path::Path;
use crate::plan_grid::{block_state, PlanGrid};
use crate::search::{entries, search};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Scan;
use plumbline_slam::grid::{Cell, CellState, GridError};
use plumbline_slam::{ScanPose, Slam};

/// What to do next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExploreStep {
    /// Fly toward this map-frame point (a lookahead point on the path to the goal, or the
    /// vehicle's own position while a plan is being confirmed), m.
    Waypoint(Vec2),
    /// Exploration is over; the mission goes home.
    Done(DoneReason),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DoneReason {
    /// No frontier the vehicle can reach is left (for
    /// [`ExploreConfig::no_frontier_confirm_s`]).
    NoReachableFrontier,
    /// The known free area stopped growing for [`ExploreConfig::coverage_stall_s`].
    CoverageStalled,
}

/// Counts for a summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExploreStats {
    pub plans: usize,
    /// Plans that found no frontier in the window round the vehicle and searched the whole
    /// map.
    pub full_map_plans: usize,
    pub goals_given_up: usize,
    pub map_rebuilds: usize,
    /// Known free area when the whole map was last planned on, m².
    pub known_free_m2: f32,
}

/// The planning grid of the whole map and when it was made.
struct FullGrid {
    made_s: f64,
    version: u64,
    grid: PlanGrid,
}

/// The current goal and the path to it.
struct Plan {
    goal: Vec2,
    path: Path,
    made_s: f64,
    map_version: u64,
    /// When this goal (or one within the unreachable radius of it) was first chosen.
    pursued_since_s: f64,
    /// The window round the vehicle held no frontier; the plan is over the whole map.
    whole_map: bool,
}

pub struct Explorer {
    config: ExploreConfig,
    map: LiveMap,
    full: Option<FullGrid>,
    home: Option<Vec2>,
    now_s: f64,
    plan: Option<Plan>,
    /// When and at which map version the last plan that found nothing was tried.
    last_empty: Option<(f64, u64)>,
    given_up: Vec<Vec2>,
    /// Places the vehicle could not get past; plans keep [`ExploreConfig::blocked_radius_m`]
    /// away from them.
    blocked: Vec<Vec2>,
    /// Largest known free area that counted as growth, and when.
    coverage: (f32, f64),
    no_frontier_since: Option<f64>,
    done: Option<DoneReason>,
    /// The last finite position `next` was given.
    last_position: Option<Vec2>,
    stats: ExploreStats,
}

impl Explorer {
    pub fn new(config: ExploreConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        let map = LiveMap::new(
            config.grid,
            config.map_range_m,
            config.rebuild_keyframes_per_scan,
        )
        .map_err(|e| ConfigError(format!("grid: {e}")))?;
        Ok(Self {
            config,
            map,
            full: None,
            home: None,
            now_s: 0.0,
            plan: None,
            last_empty: None,
            given_up: Vec::new(),
            blocked: Vec::new(),
            coverage: (0.0, f64::NAN),
            no_frontier_since: None,
            done: None,
            last_position: None,
            stats: ExploreStats::default(),
        })
    }

    pub fn config(&self) -> &ExploreConfig {
        &self.config
    }

    /// The live map (for plots and for the map error).
    pub fn map(&self) -> &LiveMap {
        &self.map
    }

    /// The take-off point in the map frame: the first pose observed unless set.
    pub fn home(&self) -> Option<Vec2> {
        self.home
    }

    /// The frontier cell being flown to, map frame (for plots and logs).
    pub fn goal(&self) -> Option<Vec2> {
        self.plan.as_ref().map(|p| p.goal)
    }

    /// The planned path to the goal, from where the vehicle was when it was planned.
    pub fn path(&self) -> Option<&Path> {
        self.plan.as_ref().map(|p| &p.path)
    }

    pub fn set_home(&mut self, home: Vec2) {
        self.home = Some(home);
    }

    /// From now on plans keep [`ExploreConfig::blocked_radius_m`] away from `at` (map frame):
    /// the vehicle made no progress there, so the map's free space there is not to be trusted.
    /// The next plan is made on a fresh grid.
    pub fn block(&mut self, at: Vec2) {
        if at.is_finite() {
            self.blocked.push(at);
            self.full = None;
            self.plan = None;
        }
    }

    pub fn stats(&self) -> ExploreStats {
        ExploreStats {
            map_rebuilds: self.map.rebuilds(),
            ..self.stats
        }
    }

    /// Takes in a scan `slam` has just placed (`at` from [`Slam::add_scan`]); its stamp is the
    /// explorer's clock. A keyframe the grid refuses is reported; the map keeps the rest.
    pub fn observe<const N: usize>(
        &mut self,
        slam: &Slam<'_, N>,
        scan: &Scan<N>,
        at: &ScanPose,
    ) -> Result<MapUpdate, GridError> {
        if scan.stamp_s.is_finite() {
            self.now_s = scan.stamp_s;
        }
        if self.home.is_none() && at.pose.is_finite() {
            self.home = Some(at.pose.translation());
        }
        if self.coverage.1.is_nan() {
            self.coverage.1 = self.now_s;
        }
        self.map.update(slam, scan, at)
    }

    /// Advances the clock without a scan (a replay or a test with a hand-made map).
    pub fn set_time(&mut self, now_s: f64) {
        if now_s.is_finite() {
            self.now_s = now_s;
            if self.coverage.1.is_nan() {
                self.coverage.1 = now_s;
            }
        }
    }

    /// The live map, for tests and replays that build it without SLAM.
    pub fn map_mut(&mut self) -> &mut LiveMap {
        &mut self.map
    }

    /// Where to fly from `pose` (map frame).
    pub fn next(&mut self, pose: Pose2) -> ExploreStep {
        if let Some(reason) = self.done {
            return ExploreStep::Done(reason);
        }
        let p = pose.translation();
        if !p.is_finite() {
            // No position to plan from: hold the last finite one (or home) rather than hand a
            // NaN to the velocity field.
            return ExploreStep::Waypoint(self.last_position.or(self.home).unwrap_or(Vec2::ZERO));
        }
        self.last_position = Some(p);
        self.full_grid(false);
        if self.now_s - self.coverage.1 >= f64::from(self.config.coverage_stall_s) {
            return self.finish(DoneReason::CoverageStalled);
        }
        if let Some(plan) = &self.plan {
            let reached = (plan.goal - p).norm() <= self.config.goal_reached_m;
            let seen = !self.still_frontier(plan.goal);
            let late = self.now_s - plan.pursued_since_s >= f64::from(self.config.goal_timeout_s);
            if (reached || late) && !seen {
                self.given_up.push(plan.goal);
                self.stats.goals_given_up += 1;
            }
            // A plan that needed the whole map (the frontier is far) is renewed as often as
            // the whole map's grid, so a long way to a far frontier is not planned anew
            // every second.
            let interval = if plan.whole_map {
                self.config.full_map_interval_s
            } else {
                self.config.replan_interval_s
            };
            let stale = plan.map_version != self.map.version()
                && self.now_s - plan.made_s >= f64::from(interval);
            if reached || seen || late || stale {
                self.replan(p);
            }
        } else {
            let retry = self.last_empty.is_none_or(|(t, version)| {
                version != self.map.version()
                    || self.now_s - t >= f64::from(self.config.replan_interval_s)
            });
            if retry {
                self.replan(p);
            }
        }
        if let Some(reason) = self.done {
            return ExploreStep::Done(reason);
        }
        // A plan within the window leads to a frontier a few metres off, across space the
        // lidar sees now, and its look-ahead is taken as it is. Held back to the legs the
        // window's grid allows, it collapsed to one step whenever a weaving vehicle stood
        // nearer a wall than plans like to keep, so flights down a corridor being explored
        // crawled and left its unobserved axis unmeasured for longer. A whole-map plan may
        // lead round corners far away, so its look-ahead is held in sight.
        let distance_m = self.config.lookahead_m;
        match self.plan.take() {
            Some(plan) => {
                let w = if plan.whole_map {
                    self.lookahead_on(&plan.path, p, distance_m)
                } else {
                    plan.path.lookahead(p, distance_m)
                };
                self.plan = Some(plan);
                ExploreStep::Waypoint(w)
            }
            None => ExploreStep::Waypoint(p),
        }
    }

    /// The point `distance_m` along `path` ahead of `p`, or nearer where the straight leg to
    /// it would cut a corner of the whole map's planning grid ([`PlanGrid::leg_clear`]): the
    /// velocity field flies straight at it, so it must be in sight along a leg the path could
    /// have taken. `path` must have been planned on that grid (the way home) or an older one.
    pub fn lookahead_on(&mut self, path: &Path, p: Vec2, distance_m: f32) -> Vec2 {
        let step_m = self.config.plan_cell_m;
        let g = self.full_grid(false);
        path.lookahead_in_sight(p, distance_m, step_m, |a, b| g.leg_clear(a, b))
    }

    /// The path from `pose` to the take-off point over the map's safe cells, with its length;
    /// `None` if no take-off point is known or no safe way leads there.
    pub fn path_home(&mut self, pose: Pose2) -> Option<Path> {
        let home = self.home?;
        let p = pose.translation();
        let reach = self.config.r_min_m() + self.config.plan_cell_m;
        let g = self.full_grid(false);
        let starts = entries(g, p, reach);
        let goals = entries(g, home, reach);
        let found = search(
            g,
            &starts,
            |k| goals.iter().any(|&(c, _)| c == k),
            |k| ((g.center(k) - home).norm() - reach).max(0.0),
        )?;
        Some(Path::through(g, p, &found.cells, Some(home)))
    }

    /// The planning grid of the whole map, made again when the map changed and the grid is
    /// older than [`ExploreConfig::full_map_interval_s`], or at once if `fresh`. The known
    /// free area (coverage) is measured on it.
    fn full_grid(&mut self, fresh: bool) -> &PlanGrid {
        let (version, now) = (self.map.version(), self.now_s);
        let interval = f64::from(self.config.full_map_interval_s);
        if self
            .full
            .as_ref()
            .is_some_and(|f| f.version != version && (fresh || now - f.made_s >= interval))
        {
            self.full = None;
        }
        let (map, config, coverage, stats, blocked) = (
            &self.map,
            &self.config,
            &mut self.coverage,
            &mut self.stats,
            &self.blocked,
        );
        &self
            .full
            .get_or_insert_with(|| {
                let mut grid =
                    PlanGrid::new(map.grid(), config.plan_factor(), config.clearance(), None);
                grid.block(blocked, config.blocked_radius_m);
                let free_m2 = grid.free_area_m2();
                stats.known_free_m2 = free_m2;
                if free_m2 >= coverage.0 + config.coverage_growth_m2 {
                    *coverage = (free_m2, now);
                }
                FullGrid {
                    made_s: now,
                    version,
                    grid,
                }
            })
            .grid
    }

    /// Whether the planning cell holding `goal` is still a frontier in the live map (checked
    /// on the map's cells, without building the planning grid).
    fn still_frontier(&self, goal: Vec2) -> bool {
        let f = self.config.plan_factor();
        let grid = self.map.grid();
        let fine = grid.frame().cell_of(goal);
        let corner = |di: i32, dj: i32| {
            Cell::new(
                (fine.i.div_euclid(f) + di) * f,
                (fine.j.div_euclid(f) + dj) * f,
            )
        };
        block_state(grid, corner(0, 0), f) == CellState::Free
            && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(di, dj)| block_state(grid, corner(di, dj), f) == CellState::Unknown)
    }

    fn finish(&mut self, reason: DoneReason) -> ExploreStep {
        self.done = Some(reason);
        self.plan = None;
        ExploreStep::Done(reason)
    }

    /// Chooses the nearest reachable frontier and plans to it: first within the window round
    /// the vehicle, and over the whole map when the window holds none.
    fn replan(&mut self, p: Vec2) {
        self.stats.plans += 1;
        let (now, version, config) = (self.now_s, self.map.version(), self.config);
        let mut window = PlanGrid::new(
            self.map.grid(),
            config.plan_factor(),
            config.clearance(),
            Some((p, config.plan_window_m)),
        );
        window.block(&self.blocked, config.blocked_radius_m);
        let mut plan = nearest_frontier(&window, p, &config, &self.given_up);
        let whole_map = !matches!(plan, Planned::To(..));
        if whole_map {
            self.stats.full_map_plans += 1;
            let given_up = std::mem::take(&mut self.given_up);
            plan = nearest_frontier(self.full_grid(true), p, &config, &given_up);
            self.given_up = given_up;
        }
        match plan {
            Planned::To(goal, path) => {
                let pursued_since_s = match &self.plan {
                    Some(old) if (old.goal - goal).norm() <= config.unreachable_radius_m => {
                        old.pursued_since_s
                    }
                    _ => now,
                };
                self.plan = Some(Plan {
                    goal,
                    path,
                    made_s: now,
                    map_version: version,
                    pursued_since_s,
                    whole_map,
                });
                self.no_frontier_since = None;
                self.last_empty = None;
            }
            Planned::Unmapped => {
                // The map has not caught up with the vehicle (a keyframe still to be drawn
                // after it flew into space it saw no return from): that says nothing about the
                // frontiers. The old plan, if any, is flown on until the map covers the vehicle.
                self.last_empty = Some((now, version));
            }
            Planned::NoFrontier => {
                self.plan = None;
                self.last_empty = Some((now, version));
                let since = *self.no_frontier_since.get_or_insert(now);
                if now - since >= f64::from(config.no_frontier_confirm_s) {
                    self.finish(DoneReason::NoReachableFrontier);
                }
            }
        }
    }
}

/// What a search for the nearest frontier found.
enum Planned {
    /// The goal and the path to it.
    To(Vec2, Path),
    /// No frontier the vehicle can reach.
    NoFrontier,
    /// No safe cell to start from: the vehicle stands where the map is not drawn (or is boxed
    /// in by what it shows).
    Unmapped,
}

/// The nearest frontier cell by path over `g` from `p` that belongs to a cluster big enough
/// and lies clear of every goal given up, with the path to it.
fn nearest_frontier(g: &PlanGrid, p: Vec2, config: &ExploreConfig, given_up: &[Vec2]) -> Planned {
    let min_cells = (config.min_frontier_m / config.plan_cell_m).ceil() as usize;
    let frontiers = clusters(g, min_cells);
    let wanted = |k: usize| {
        frontiers.cluster_of[k] != NO_CLUSTER
            && given_up
                .iter()
                .all(|&q| (g.center(k) - q).norm() > config.unreachable_radius_m)
    };
    let starts = entries(g, p, config.r_min_m() + config.plan_cell_m);
    if starts.is_empty() {
        return Planned::Unmapped;
    }
    let Some(found) = search(g, &starts, wanted, |_| 0.0) else {
        return Planned::NoFrontier;
    };
    let Some(&last) = found.cells.last() else {
        return Planned::NoFrontier;
    };
    Planned::To(g.center(last), Path::through(g, p, &found.cells, None))
}
