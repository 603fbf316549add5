//! The one parameter set of the guidance, with units in every name and a check that rejects
//! values the algorithms cannot work with (an error, never a panic at run time).

use core::fmt;

/// Parameters of wall extraction, the velocity field and the heading rules (seed 002, sec. II.B.1).
///
/// Defaults suit the simulator's vehicle (0.35 m radius with propellers) in office-like
/// buildings (2 m corridors, 1.2 m doors, rooms of 4-5 m): see each field for why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuidanceConfig {
    /// Radius of the vehicle seen from above, propellers included, m. Default 0.35 m (the
    /// simulated airframe). Gaps must be wider than twice this to be flown through.
    pub vehicle_radius_m: f32,
    /// Clearance kept beyond the vehicle radius, m. Default 0.15 m: covers estimate error and
    /// overshoot of the velocity loop. `r_min` = radius + margin (seed 002's minimum safe distance).
    pub clearance_margin_m: f32,
    /// Desired distance from the followed wall, `r_goal` of seed 002 eq. 1, m. Default 1.2 m:
    /// a 2 m corridor (under 2 `r_goal`) is flown centred, a 4 m room is followed along its walls,
    /// and a 4 m lidar still sees the opposite side of a corridor from there.
    pub r_goal_m: f32,
    /// Velocity gain `K_v` of seed 002 eq. 2, m²/s (each beam adds a unit vector divided by a
    /// distance in m). Default 1.5 m²/s: along a single wall at `r_goal` seen by 360 beams the
    /// field reaches the speed limit; 1.2 m from the long wall of a 6 m x 4 m room, 0.43 m/s.
    pub k_v_m2_s: f32,
    /// How much `K_v` grows as the nearest range falls from `r_goal` to `r_min`: the gain is
    /// `K_v (1 + boost · s)` with `s` going linearly from 0 to 1. Dimensionless, default 2.0 (three
    /// times the gain at `r_min`), the seed's obstacle avoidance built into the field.
    pub k_v_boost: f32,
    /// Smallest `|r - r_min|` used as a divisor in eq. 2, m. Default 0.05 m: the seed's weight is
    /// singular at `r_min`; this bounds one beam's weight to 20 /m.
    pub weight_floor_m: f32,
    /// Largest commanded horizontal speed, m/s. Default 0.5 m/s: indoor flight with a 4 m lidar
    /// leaves eight seconds of sight at this speed.
    pub max_speed_m_s: f32,
    /// Speed along a corridor flown centred, and toward a waypoint, m/s. Default 0.4 m/s.
    pub cruise_speed_m_s: f32,
    /// Lateral speed per metre of off-centre error in a corridor, 1/s. Default 1.0 /s.
    pub centring_gain_1_s: f32,
    /// Speed toward a waypoint per metre of remaining distance (capped at the cruise speed),
    /// 1/s. Default 1.0 /s: the vehicle slows within 0.4 m of the waypoint instead of overshooting.
    pub waypoint_gain_1_s: f32,
    /// Largest speed toward an obstacle per metre of clearance beyond `r_min`, 1/s. Default
    /// 1.0 /s: the approach slows exponentially (time constant 1 s) and never reaches `r_min`
    /// while the velocity loop follows. Applies in every mode after everything else.
    pub approach_rate_1_s: f32,
    /// How long hits within the guard's reach are remembered, s (0: not at all). Default 1.0 s:
    /// five revolutions of a 5 Hz lidar, long enough to pass a wall end that vanishes when seen
    /// edge-on, short enough that estimate drift and walking people leave no lasting ghosts.
    pub obstacle_memory_s: f32,
    /// How long a remembered hit is kept while the vehicle stays within its stopping distance
    /// (`max_speed_m_s / approach_rate_1_s`) of where it last saw it, s (at most
    /// `obstacle_memory_s` has no effect). Default 10 s: a vehicle that lingers in a doorway
    /// for seconds and then turns along the wall still sees the jamb that vanished edge-on,
    /// while where a walking person stood stops counting once the vehicle has moved on, and
    /// after this long even where it has not.
    pub obstacle_hold_s: f32,
    /// Slowest closing speed of a surface that is taken as a mover to sidestep, m/s. Default
    /// 0.25 m/s: well above what estimate jitter and range noise make a wall appear to move
    /// between revolutions (a few cm a revolution, averaged over five beams), under a slow walk.
    pub mover_min_closing_m_s: f32,
    /// Fastest a mover is believed to go, m/s: a hit further from every hit of the previous
    /// revolution than this speed allows is a surface seen for the first time, not a mover.
    /// Default 2.0 m/s: a brisk walk with room to spare.
    pub mover_max_speed_m_s: f32,
    /// A mover is sidestepped when it would reach `r_min` within this time, s. Default 3.0 s:
    /// stepping `r_min` plus a person's half width across its way takes under 2 s at the speed
    /// limit, and the rest covers the velocity loop's lag.
    pub evade_horizon_s: f32,
    /// Narrowest opening taken as a gap to fly through, m. Default 1.0 m = 2 `r_min`. Must be
    /// wider than the vehicle (2 × radius): narrower openings are treated as wall.
    pub min_gap_width_m: f32,
    /// PRLS: largest distance of a new point from the line fitted so far, m. Default 0.05 m:
    /// five times the range noise of the simulated lidars, well under a door jamb's depth.
    pub line_tolerance_m: f32,
    /// PRLS: consecutive hits further apart than this end a segment, m. Default 0.3 m: wider
    /// than beam spacing on a wall 6 m away seen at 30° (1° beams), narrower than the vehicle.
    pub max_point_spacing_m: f32,
    /// PRLS: consecutive beams more than this apart in angle end a segment, rad. Default 0.1 rad
    /// (5.7°): every supported lidar samples finer, so a larger step is a hole in the scan.
    pub max_beam_step_rad: f32,
    /// PRLS: fewest hits in a segment. Default 3: two points always fit a line.
    pub min_segment_points: u16,
    /// PRLS: shortest segment, m. Default 0.1 m: shorter runs are clutter (a chair leg), not wall.
    pub min_segment_length_m: f32,
    /// Where the heading rules start looking, counter-clockwise from body x, rad. Default -2π/3
    /// (120° to the right): the first beam of seed 002's 240° Hokuyo URG-04LX.
    pub rule_start_rad: f32,
    /// How far counter-clockwise the heading rules look, rad. Default 4π/3 (240°, the seed's
    /// field of view), so a 360° lidar decides as the seed's lidar did.
    pub rule_sweep_rad: f32,
}

impl Default for GuidanceConfig {
    fn default() -> Self {
        use core::f32::consts::PI;
        Self {
            vehicle_radius_m: 0.35,
            clearance_margin_m: 0.15,
            r_goal_m: 1.2,
            k_v_m2_s: 1.5,
            k_v_boost: 2.0,
            weight_floor_m: 0.05,
            max_speed_m_s: 0.5,
            cruise_speed_m_s: 0.4,
            centring_gain_1_s: 1.0,
            waypoint_gain_1_s: 1.0,
            approach_rate_1_s: 1.0,
            obstacle_memory_s: 1.0,
            obstacle_hold_s: 10.0,
            mover_min_closing_m_s: 0.25,
            mover_max_speed_m_s: 2.0,
            evade_horizon_s: 3.0,
            min_gap_width_m: 1.0,
            line_tolerance_m: 0.05,
            max_point_spacing_m: 0.3,
            max_beam_step_rad: 0.1,
            min_segment_points: 3,
            min_segment_length_m: 0.1,
            rule_start_rad: -2.0 * PI / 3.0,
            rule_sweep_rad: 4.0 * PI / 3.0,
        }
    }
}

/// A parameter the guidance cannot work with: which field, its value, and what it must be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuidanceConfigError {
    pub field: &'static str,
    pub value: f32,
    pub requirement: &'static str,
}

impl fmt::Display for GuidanceConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "guidance setting `{}` = {} is not usable: it must be {}",
            self.field, self.value, self.requirement
        )
    }
}

impl GuidanceConfig {
    /// Seed 002's minimum safe distance: vehicle radius plus clearance margin, m.
    pub fn r_min_m(&self) -> f32 {
        self.vehicle_radius_m + self.clearance_margin_m
    }

    /// Checks every field; the first unusable one is returned.
    pub fn validate(&self) -> Result<(), GuidanceConfigError> {
        let positive = "finite and greater than 0";
        let checks: [(&'static str, f32, bool, &'static str); 24] = [
            (
                "vehicle_radius_m",
                self.vehicle_radius_m,
                is_pos(self.vehicle_radius_m),
                positive,
            ),
            (
                "clearance_margin_m",
                self.clearance_margin_m,
                is_non_neg(self.clearance_margin_m),
                "finite and at least 0",
            ),
            (
                "r_goal_m",
                self.r_goal_m,
                is_pos(self.r_goal_m) && self.r_goal_m > self.r_min_m(),
                "finite and greater than vehicle_radius_m + clearance_margin_m",
            ),
            ("k_v_m2_s", self.k_v_m2_s, is_pos(self.k_v_m2_s), positive),
            (
                "k_v_boost",
                self.k_v_boost,
                is_non_neg(self.k_v_boost),
                "finite and at least 0",
            ),
            (
                "weight_floor_m",
                self.weight_floor_m,
                is_pos(self.weight_floor_m),
                positive,
            ),
            (
                "max_speed_m_s",
                self.max_speed_m_s,
                is_pos(self.max_speed_m_s),
                positive,
            ),
            (
                "cruise_speed_m_s",
                self.cruise_speed_m_s,
                is_pos(self.cruise_speed_m_s) && self.cruise_speed_m_s <= self.max_speed_m_s,
                "finite, greater than 0 and at most max_speed_m_s",
            ),
            (
                "centring_gain_1_s",
                self.centring_gain_1_s,
                is_pos(self.centring_gain_1_s),
                positive,
            ),
            (
                "waypoint_gain_1_s",
                self.waypoint_gain_1_s,
                is_pos(self.waypoint_gain_1_s),
                positive,
            ),
            (
                "approach_rate_1_s",
                self.approach_rate_1_s,
                is_pos(self.approach_rate_1_s),
                positive,
            ),
            (
                "obstacle_memory_s",
                self.obstacle_memory_s,
                is_non_neg(self.obstacle_memory_s),
                "finite and at least 0",
            ),
            (
                "obstacle_hold_s",
                self.obstacle_hold_s,
                is_non_neg(self.obstacle_hold_s),
                "finite and at least 0",
            ),
            (
                "mover_min_closing_m_s",
                self.mover_min_closing_m_s,
                is_pos(self.mover_min_closing_m_s),
                positive,
            ),
            (
                "mover_max_speed_m_s",
                self.mover_max_speed_m_s,
                is_pos(self.mover_max_speed_m_s)
                    && self.mover_max_speed_m_s >= self.mover_min_closing_m_s,
                "finite and at least mover_min_closing_m_s",
            ),
            (
                "evade_horizon_s",
                self.evade_horizon_s,
                is_non_neg(self.evade_horizon_s),
                "finite and at least 0 (0 sidesteps no mover)",
            ),
            (
                "min_gap_width_m",
                self.min_gap_width_m,
                self.min_gap_width_m.is_finite()
                    && self.min_gap_width_m > 2.0 * self.vehicle_radius_m,
                "finite and wider than the vehicle (2 × vehicle_radius_m)",
            ),
            (
                "line_tolerance_m",
                self.line_tolerance_m,
                is_pos(self.line_tolerance_m),
                positive,
            ),
            (
                "max_point_spacing_m",
                self.max_point_spacing_m,
                is_pos(self.max_point_spacing_m),
                positive,
            ),
            (
                "max_beam_step_rad",
                self.max_beam_step_rad,
                is_pos(self.max_beam_step_rad) && self.max_beam_step_rad < core::f32::consts::PI,
                "finite, greater than 0 and less than pi",
            ),
            (
                "min_segment_points",
                f32::from(self.min_segment_points),
                self.min_segment_points >= 2,
                "at least 2",
            ),
            (
                "min_segment_length_m",
                self.min_segment_length_m,
                is_non_neg(self.min_segment_length_m),
                "finite and at least 0",
            ),
            (
                "rule_start_rad",
                self.rule_start_rad,
                self.rule_start_rad.is_finite(),
                "finite",
            ),
            (
                "rule_sweep_rad",
                self.rule_sweep_rad,
                is_pos(self.rule_sweep_rad) && self.rule_sweep_rad <= core::f32::consts::TAU,
                "finite, greater than 0 and at most 2 pi",
            ),
        ];
        match checks.iter().find(|c| !c.2) {
            Some(&(field, value, _, requirement)) => Err(GuidanceConfigError {
                field,
                value,
                requirement,
            }),
            None => Ok(()),
        }
    }
}

fn is_pos(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

fn is_non_neg(v: f32) -> bool {
    v.is_finite() && v >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(GuidanceConfig::default().validate(), Ok(()));
        assert!((GuidanceConfig::default().r_min_m() - 0.5).abs() < 1e-6);
    }

    #[test]
    fn bad_values_name_their_field() {
        let bad = |f: fn(&mut GuidanceConfig)| {
            let mut c = GuidanceConfig::default();
            f(&mut c);
            c.validate().unwrap_err().field
        };
        assert_eq!(bad(|c| c.r_goal_m = f32::NAN), "r_goal_m");
        assert_eq!(bad(|c| c.r_goal_m = 0.4), "r_goal_m");
        assert_eq!(bad(|c| c.k_v_m2_s = -1.0), "k_v_m2_s");
        assert_eq!(bad(|c| c.cruise_speed_m_s = 2.0), "cruise_speed_m_s");
        assert_eq!(bad(|c| c.min_gap_width_m = 0.6), "min_gap_width_m");
        assert_eq!(bad(|c| c.min_segment_points = 1), "min_segment_points");
        assert_eq!(bad(|c| c.rule_sweep_rad = 7.0), "rule_sweep_rad");
        assert_eq!(bad(|c| c.obstacle_memory_s = -1.0), "obstacle_memory_s");
        assert_eq!(bad(|c| c.obstacle_hold_s = f32::NAN), "obstacle_hold_s");
        assert_eq!(
            bad(|c| c.mover_min_closing_m_s = 0.0),
            "mover_min_closing_m_s"
        );
        assert_eq!(bad(|c| c.mover_max_speed_m_s = 0.1), "mover_max_speed_m_s");
        assert_eq!(bad(|c| c.evade_horizon_s = f32::NAN), "evade_horizon_s");
        assert_eq!(
            bad(|c| c.vehicle_radius_m = f32::INFINITY),
            "vehicle_radius_m"
        );
    }

    #[test]
    fn the_error_message_says_what_to_do() {
        extern crate std;
        use std::string::ToString;
        let c = GuidanceConfig {
            min_gap_width_m: 0.5,
            ..GuidanceConfig::default()
        };
        let text = c.validate().unwrap_err().to_string();
        assert!(
            text.contains("min_gap_width_m") && text.contains("wider than the vehicle"),
            "{text}"
        );
    }
}
