//! Every tunable of exploration in one place, with units and the reason for each default.

use crate::plan_grid::Clearance;
use plumbline_slam::grid::GridConfig;

/// Exploration parameters. Distances in metres, times in seconds of the scans' clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExploreConfig {
    /// The live map (the same grid `plumbline slam --map` writes, so what the vehicle planned
    /// on is what people later open).
    pub grid: GridConfig,
    /// Beams are drawn into the live map up to this range, m (the slam command's map range).
    pub map_range_m: f32,
    /// Most keyframes a rebuild of the live map (after loop closure moved the poses) inserts
    /// per scan; the old map serves until the rebuild is complete. The building survey's 923
    /// keyframes took 50 ms in one go on a loaded machine; at 50 a scan they take 19 scans.
    pub rebuild_keyframes_per_scan: usize,
    /// Side of a planning cell, m: a whole multiple of the grid's resolution. Planning on
    /// 10 cm cells visits a quarter of the 5 cm cells and still passes a 1.2 m door.
    pub plan_cell_m: f32,
    /// The vehicle's radius, m (the simulated quadrotor's is 0.35 m).
    pub vehicle_radius_m: f32,
    /// Extra clearance kept from every obstacle on top of the radius, m. Radius plus margin
    /// is `r_min`: no planned path comes closer to a mapped obstacle, so a gap narrower than
    /// `2 r_min` is never planned through.
    pub clearance_margin_m: f32,
    /// Clearance paths keep from mapped obstacles where the map has room, m: the clearance
    /// guard's `r_min` (the guidance's), so the guard need not hold the vehicle off a path
    /// that rounds a corner closer than it allows. Only where the map has no such room (a
    /// 1.2 m door) do paths come as close as `r_min`, and the search charges `tight_cost`
    /// times the length there, so they do so for as short a stretch as they can.
    pub preferred_clearance_m: f32,
    /// Cost per metre of path closer than `preferred_clearance_m`, in metres of roomy path.
    /// Default 4: a detour of up to three times a tight stretch's length is taken to avoid it.
    pub tight_cost: f32,
    /// No path is planned within this distance of a place the vehicle was found stuck at
    /// ([`crate::Explorer::block`]), m: wide enough to close a door-sized gap that the map
    /// shows and the walls do not have.
    pub blocked_radius_m: f32,
    /// Frontier clusters shorter than this are ignored, m: single unknown cells between far
    /// beams and behind wall corners are not worth a flight.
    pub min_frontier_m: f32,
    /// The waypoint handed to the velocity field lies this far along the planned path, m.
    pub lookahead_m: f32,
    /// The plan is renewed at most this often while the map only grows, s (planning costs a
    /// pass over the map; the goal being reached or seen renews it at once).
    pub replan_interval_s: f32,
    /// Plans look for the nearest frontier within a square of this half-side round the
    /// vehicle first, m (the XV-11's range: the frontier just uncovered is usually there), and
    /// over the whole map only when the square holds none, so a plan's work does not grow
    /// with the building.
    pub plan_window_m: f32,
    /// The whole map's planning grid (coverage, the way home) is made again at most this
    /// often while the map only grows, s; a plan that needs it makes it at once.
    pub full_map_interval_s: f32,
    /// The goal counts as reached within this distance, m.
    pub goal_reached_m: f32,
    /// A goal pursued this long without being reached or seen is given up as unreachable
    /// (a person in the way, a door the map shows open that is not), s.
    pub goal_timeout_s: f32,
    /// Frontier cells within this distance of a goal given up are not chosen again, m.
    pub unreachable_radius_m: f32,
    /// Exploration is done when the known free area has grown by less than
    /// `coverage_growth_m2` for this long, s.
    pub coverage_stall_s: f32,
    /// Growth of the known free area that counts as progress, m².
    pub coverage_growth_m2: f32,
    /// Exploration is done when no reachable frontier has been found for this long, s: a
    /// person standing in the only door hides the frontier behind it for a moment.
    pub no_frontier_confirm_s: f32,
}

impl Default for ExploreConfig {
    fn default() -> Self {
        Self {
            grid: GridConfig::default(),
            map_range_m: 25.0,
            rebuild_keyframes_per_scan: 50,
            plan_cell_m: 0.1,
            vehicle_radius_m: 0.35,
            clearance_margin_m: 0.05,
            preferred_clearance_m: 0.5,
            tight_cost: 4.0,
            blocked_radius_m: 1.0,
            min_frontier_m: 0.4,
            lookahead_m: 1.0,
            replan_interval_s: 1.0,
            plan_window_m: 6.0,
            full_map_interval_s: 10.0,
            goal_reached_m: 0.3,
            goal_timeout_s: 30.0,
            unreachable_radius_m: 0.5,
            coverage_stall_s: 60.0,
            coverage_growth_m2: 1.0,
            no_frontier_confirm_s: 2.0,
        }
    }
}

/// A configuration field out of range; the text names the field, its value and what is valid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError(pub String);

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "exploration configuration: {}", self.0)
    }
}

impl std::error::Error for ConfigError {}

impl ExploreConfig {
    /// `r_min`: the vehicle radius plus the margin, m.
    pub fn r_min_m(&self) -> f32 {
        self.vehicle_radius_m + self.clearance_margin_m
    }

    /// How far plans keep from mapped obstacles.
    pub fn clearance(&self) -> Clearance {
        Clearance {
            r_min_m: self.r_min_m(),
            preferred_m: self.preferred_clearance_m,
            tight_cost: self.tight_cost,
        }
    }

    /// Fine grid cells per planning cell side.
    pub fn plan_factor(&self) -> i32 {
        (self.plan_cell_m / self.grid.resolution_m).round() as i32
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.grid
            .validate()
            .map_err(|e| ConfigError(format!("grid: {e}")))?;
        let positive = [
            ("map_range_m", self.map_range_m),
            ("plan_cell_m", self.plan_cell_m),
            ("vehicle_radius_m", self.vehicle_radius_m),
            ("lookahead_m", self.lookahead_m),
            ("goal_reached_m", self.goal_reached_m),
            ("plan_window_m", self.plan_window_m),
            ("goal_timeout_s", self.goal_timeout_s),
            ("coverage_stall_s", self.coverage_stall_s),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(ConfigError(format!(
                    "{name} is {v}; it must be finite and positive"
                )));
            }
        }
        let non_negative = [
            ("clearance_margin_m", self.clearance_margin_m),
            ("min_frontier_m", self.min_frontier_m),
            ("blocked_radius_m", self.blocked_radius_m),
            ("replan_interval_s", self.replan_interval_s),
            ("full_map_interval_s", self.full_map_interval_s),
            ("unreachable_radius_m", self.unreachable_radius_m),
            ("coverage_growth_m2", self.coverage_growth_m2),
            ("no_frontier_confirm_s", self.no_frontier_confirm_s),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ConfigError(format!(
                    "{name} is {v}; it must be finite and not negative"
                )));
            }
        }
        if !(self.preferred_clearance_m.is_finite() && self.preferred_clearance_m >= self.r_min_m())
        {
            return Err(ConfigError(format!(
                "preferred_clearance_m is {}; it must be at least r_min = vehicle_radius_m + \
                 clearance_margin_m = {} m",
                self.preferred_clearance_m,
                self.r_min_m()
            )));
        }
        if !(self.tight_cost.is_finite() && self.tight_cost >= 1.0) {
            return Err(ConfigError(format!(
                "tight_cost is {}; it must be finite and at least 1",
                self.tight_cost
            )));
        }
        if self.rebuild_keyframes_per_scan == 0 {
            return Err(ConfigError(
                "rebuild_keyframes_per_scan is 0; it must be at least 1".into(),
            ));
        }
        let r = self.grid.resolution_m;
        let ratio = self.plan_cell_m / r;
        if !((ratio - ratio.round()).abs() < 1e-3 && (1.0..=16.0).contains(&ratio.round())) {
            return Err(ConfigError(format!(
                "plan_cell_m {} must be 1 to 16 times the grid resolution {r} m",
                self.plan_cell_m
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_valid_and_each_bad_field_is_named() {
        assert_eq!(ExploreConfig::default().validate(), Ok(()));
        assert_eq!(ExploreConfig::default().plan_factor(), 2);
        type Spoil = fn(&mut ExploreConfig);
        let cases: [(&str, Spoil); 7] = [
            ("vehicle_radius_m", |c| c.vehicle_radius_m = -0.1),
            ("lookahead_m", |c| c.lookahead_m = f32::NAN),
            ("clearance_margin_m", |c| c.clearance_margin_m = -1.0),
            ("plan_cell_m", |c| c.plan_cell_m = 0.07),
            ("grid", |c| c.grid.resolution_m = 0.0),
            ("preferred_clearance_m", |c| c.preferred_clearance_m = 0.3),
            ("tight_cost", |c| c.tight_cost = 0.5),
        ];
        for (field, spoil) in cases {
            let mut c = ExploreConfig::default();
            spoil(&mut c);
            let e = c.validate().unwrap_err();
            assert!(e.0.contains(field), "{field}: {e}");
        }
    }
}
