//! The exploration mission's half of the flight part: what the companion asked for, how fresh
//! it is, and what the battery allows.
//!
//! take off -> hold -> explore -> return -> land at the take-off point. The companion starts
//! exploring ([`MissionCommand::StartExplore`], taken once the take-off hold is reached) and
//! ends it ([`MissionCommand::ExploreDone`]); the time budget and the battery can end it first.
//! While exploring or returning the vehicle flies the companion's latest setpoint, mapped from
//! the companion's map frame into the world frame through the pose-fix anchor; a setpoint older
//! than `setpoint_timeout_s` is stale and the vehicle holds where it was when it went stale;
//! no setpoint for `companion_lost_s` lands in place ([`FailsafeReason::CompanionLost`]), and
//! so does a companion that finds its leg stuck ([`MissionCommand::LandHere`],
//! [`FailsafeReason::NoProgress`]).
//!
//! The battery decision (seed 002's low-voltage landing, extended for a mission): the remaining
//! energy is estimated from the smoothed pack voltage; the energy needed to get home is
//! `flight_power_w` times the time to fly the companion's path home at `return_speed_m_s` and
//! to land. Exploration returns when the remaining energy is within `lookahead_s` of flight of
//! that need with `margin_fraction` on top, or when the voltage failsafe trips and the need is
//! still covered; it lands in place when the need with its margin is no longer covered (a path
//! home that grew, a sagging pack) or the voltage failsafe trips without a known path home. A
//! return in progress lands in place only if the voltage failsafe trips and the way home is no
//! longer covered. The critical-battery, lidar-lost and estimate-invalid failsafes, the kill
//! switch and manual takeover act exactly as without a mission.

use crate::estimate::pose_fix::CompanionFrame;
use crate::guidance::{ApproachLimit, GuidanceConfig};
use crate::msgs::{
    CompanionMessages, CompanionSetpoint, EstimatedState, FailsafeReason, FlightMode,
    MissionCommand, SetpointTarget,
};
use core::cmp::Ordering;
use libm::hypotf;

/// Mission timing, home and energy settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionConfig {
    /// A setpoint older than this (s) is stale: the vehicle holds. Three XV-11 revolutions, so
    /// one late revolution of the companion does not stop the vehicle.
    pub setpoint_timeout_s: f32,
    /// No fresh setpoint for this long (s) while exploring or returning lands in place.
    pub companion_lost_s: f32,
    /// Exploring ends after this long (s) and the vehicle returns.
    pub explore_budget_s: f32,
    /// The return ends, and the landing starts, this close (m, horizontal) to the take-off point.
    pub home_tolerance_m: f32,
    pub energy: EnergyConfig,
    /// The flight part's own check of every mission setpoint against the latest revolution:
    /// no faster toward a hit than this allows, in the frame the setpoint is flown in (see
    /// [`crate::guidance::guard`]). The guidance's rule, so a setpoint the companion guarded in
    /// the same frame passes unchanged.
    pub guard: ApproachLimit,
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self {
            setpoint_timeout_s: 0.6,
            companion_lost_s: 5.0,
            explore_budget_s: 600.0,
            home_tolerance_m: 0.15,
            energy: EnergyConfig::default(),
            guard: ApproachLimit::from(&GuidanceConfig::default()),
        }
    }
}

/// The onboard energy model. Defaults: the simulator's F450 (3S 2200 mAh, about 130 W in
/// hover). Remaining energy goes linearly with the loaded pack voltage between `empty_v` and
/// `full_v`: crude on a LiPo's plateau, and a current sensor would do better, but it needs
/// nothing the vehicle does not already measure. `empty_v` is the critical-battery threshold,
/// below the low one: the energy between the two is what a return after the low-battery
/// failsafe flies on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyConfig {
    /// Energy (Wh) the pack delivers between `full_v` and `empty_v`.
    pub usable_energy_wh: f32,
    /// Loaded pack voltage (V) of a full pack.
    pub full_v: f32,
    /// Loaded pack voltage (V) at which the usable energy is spent.
    pub empty_v: f32,
    /// Time constant (s) of the voltage smoothing: load steps sag the voltage for a moment. Half
    /// the battery failsafe's debounce, so the estimate has settled when the failsafe trips.
    pub voltage_smoothing_s: f32,
    /// Electrical power (W) while flying.
    pub flight_power_w: f32,
    /// Ground speed (m/s) assumed along the path home.
    pub return_speed_m_s: f32,
    /// Energy kept over the estimated need of the way home, as a fraction of it.
    pub margin_fraction: f32,
    /// Exploring stops this much flight time (s) before the margin would be eaten into.
    pub lookahead_s: f32,
}

impl Default for EnergyConfig {
    fn default() -> Self {
        Self {
            usable_energy_wh: 22.0,
            full_v: 12.6,
            empty_v: 9.9,
            voltage_smoothing_s: 0.5,
            flight_power_w: 130.0,
            return_speed_m_s: 0.5,
            margin_fraction: 0.3,
            lookahead_s: 20.0,
        }
    }
}

/// What the battery allows for the way home.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Energy {
    /// No path length or voltage yet: only the voltage failsafe speaks.
    #[default]
    Unknown,
    /// Enough for more exploring and the way home with its margin.
    Plenty,
    /// Still covers the way home with its margin, but only just: turn back now.
    TurnBack,
    /// No longer covers the way home with its margin.
    Short,
}

/// What the mission tells the supervisor this step (the default: no mission).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MissionStatus {
    /// The companion asked to start exploring.
    pub start_requested: bool,
    /// The companion said exploring is done, or the time budget is spent.
    pub explore_over: bool,
    pub energy: Energy,
    /// No setpoint for `companion_lost_s` in this mission mode.
    pub companion_silent: bool,
    /// Within `home_tolerance_m` of the take-off point.
    pub at_home: bool,
    /// The companion has sent something within `companion_lost_s`: a mission can be flown.
    pub companion_present: bool,
    /// The companion asked to land in place ([`MissionCommand::LandHere`]).
    pub land_requested: bool,
}

/// Companion inputs that were refused, and the steps spent holding for want of a setpoint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MissionCounters {
    /// Non-finite, or timed more than `setpoint_timeout_s` from the step that received it.
    pub bad_setpoints: u32,
    /// Non-finite or negative path-home lengths.
    pub bad_path_home: u32,
    /// Steps flown holding because the setpoint was stale.
    pub stale_steps: u32,
    /// Steps whose target the flight part's guard pulled back from a hit.
    pub guarded_steps: u32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mission {
    pub config: MissionConfig,
    start_requested: bool,
    done: bool,
    /// The companion asked to land in place.
    land_requested: bool,
    /// When the current mission mode began (s): the budget's start and the silence's floor.
    mode_since_t_s: f64,
    /// The latest setpoint of the current mission mode (map frame).
    setpoint: Option<CompanionSetpoint>,
    /// Where to hold while the setpoint is stale (world x, y, yaw).
    stale_hold: Option<[f32; 3]>,
    path_home_m: Option<f32>,
    voltage_v: Option<f32>,
    /// The take-off point in the companion's map frame, once the map is anchored.
    home_map: Option<[f32; 2]>,
    /// When the companion last sent anything.
    heard_t_s: Option<f64>,
    counters: MissionCounters,
}

impl Mission {
    pub fn new(config: MissionConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    pub fn counters(&self) -> &MissionCounters {
        &self.counters
    }

    /// Counts a step whose target the flight part's guard pulled back.
    pub(super) fn count_guarded(&mut self) {
        self.counters.guarded_steps = self.counters.guarded_steps.saturating_add(1);
    }

    /// Takes in what arrived at `t_s`; `battery_v` is a finite reading or `None`.
    pub fn observe(&mut self, t_s: f64, m: &CompanionMessages, battery_v: Option<f32>, dt: f32) {
        if m.pose.is_some()
            || m.setpoint.is_some()
            || m.command.is_some()
            || m.path_home_m.is_some()
        {
            self.heard_t_s = Some(t_s);
        }
        match m.command {
            Some(MissionCommand::StartExplore) => self.start_requested = true,
            Some(MissionCommand::ExploreDone) => self.done = true,
            Some(MissionCommand::LandHere) => self.land_requested = true,
            None => {}
        }
        if let Some(mut sp) = m.setpoint {
            // A setpoint already stale, or from further in the future than that (a companion
            // clock gone wrong), is refused; one from the future ages from its arrival, so a
            // companion that stops talking is noticed whatever its clock says.
            let age_s = (t_s - sp.t_s) as f32;
            if setpoint_is_finite(&sp) && age_s.abs() <= self.config.setpoint_timeout_s {
                sp.t_s = sp.t_s.min(t_s);
                self.setpoint = Some(sp);
            } else {
                self.counters.bad_setpoints = self.counters.bad_setpoints.saturating_add(1);
            }
        }
        match m.path_home_m {
            Some(len) if len.is_finite() && len >= 0.0 => self.path_home_m = Some(len),
            Some(_) => self.counters.bad_path_home = self.counters.bad_path_home.saturating_add(1),
            None => {}
        }
        if let Some(v) = battery_v {
            let tau = self.config.energy.voltage_smoothing_s;
            let k = if tau > 0.0 { (dt / tau).min(1.0) } else { 1.0 };
            self.voltage_v = Some(self.voltage_v.map_or(v, |f| f + k * (v - f)));
        }
    }

    /// Mode entry: a new mission mode starts its clock and forgets the last leg's setpoint;
    /// exploring takes up the start request (a hold after a manual takeover waits for a new
    /// one); a disarm ends the mission.
    pub fn enter(&mut self, mode: FlightMode, t_s: f64) {
        self.mode_since_t_s = t_s;
        self.setpoint = None;
        self.stale_hold = None;
        match mode {
            FlightMode::Explore => self.start_requested = false,
            FlightMode::Disarmed => {
                *self = Self {
                    heard_t_s: self.heard_t_s,
                    ..Self::new(self.config)
                }
            }
            _ => {}
        }
    }

    /// Remembers the take-off point in the map frame once the map is anchored, so a later
    /// re-anchoring moves it with the map.
    pub fn track_home(&mut self, home_world: [f32; 2], frame: &CompanionFrame) {
        if self.home_map.is_none() && frame.counters().anchors > 0 {
            self.home_map = Some(frame.to_map(home_world));
        }
    }

    /// The take-off point in the world frame now.
    pub fn home(&self, home_world: [f32; 2], frame: &CompanionFrame) -> [f32; 2] {
        self.home_map.map_or(home_world, |h| frame.to_world(h))
    }

    /// The facts the supervisor decides on. `here` is the estimate, `home` the take-off point
    /// in the world frame, `landing_s` the time a landing from the mission height takes.
    pub fn status(
        &self,
        t_s: f64,
        here: [f32; 2],
        home: [f32; 2],
        landing_s: f32,
    ) -> MissionStatus {
        let c = &self.config;
        let in_mode_s = (t_s - self.mode_since_t_s) as f32;
        let silent_s = self.setpoint.map_or(in_mode_s, |sp| {
            ((t_s - sp.t_s.max(self.mode_since_t_s)) as f32).min(in_mode_s)
        });
        MissionStatus {
            start_requested: self.start_requested,
            explore_over: self.done || in_mode_s >= c.explore_budget_s,
            energy: self.energy(landing_s),
            companion_silent: silent_s > c.companion_lost_s,
            at_home: hypotf(here[0] - home[0], here[1] - home[1]) <= c.home_tolerance_m,
            companion_present: self
                .heard_t_s
                .is_some_and(|at| ((t_s - at) as f32) <= c.companion_lost_s),
            land_requested: self.land_requested,
        }
    }

    fn energy(&self, landing_s: f32) -> Energy {
        let c = &self.config.energy;
        let (Some(path_m), Some(v)) = (self.path_home_m, self.voltage_v) else {
            return Energy::Unknown;
        };
        let charge = ((v - c.empty_v) / (c.full_v - c.empty_v)).clamp(0.0, 1.0);
        let remaining_wh = c.usable_energy_wh * charge;
        let home_s = path_m / c.return_speed_m_s.max(0.01) + landing_s.max(0.0);
        let need_wh = c.flight_power_w * home_s / 3600.0 * (1.0 + c.margin_fraction);
        let lookahead_wh = c.flight_power_w * c.lookahead_s / 3600.0;
        // A NaN (from a nonsensical configuration) counts as short: land rather than guess.
        match remaining_wh.partial_cmp(&need_wh) {
            None | Some(Ordering::Less) => Energy::Short,
            _ if remaining_wh < need_wh + lookahead_wh => Energy::TurnBack,
            _ => Energy::Plenty,
        }
    }

    /// The horizontal target and heading to fly now in a mission mode, in the world frame: the
    /// companion's setpoint, or the hold point while it is stale or `hold` is asked for. A velocity setpoint becomes
    /// a point `v / position_gain` ahead of the estimate, which the position loop (proportional,
    /// gain `position_gain` 1/s) turns back into exactly that velocity.
    pub fn target(
        &mut self,
        t_s: f64,
        frame: &CompanionFrame,
        e: &EstimatedState,
        position_gain: f32,
        hold: bool,
    ) -> [f32; 3] {
        let timeout_s = self.config.setpoint_timeout_s;
        let fresh = self
            .setpoint
            .filter(|sp| !hold && ((t_s - sp.t_s) as f32) <= timeout_s);
        let here = [e.position_m[0], e.position_m[1]];
        let target = fresh.and_then(|sp| match sp.target {
            SetpointTarget::Position {
                position_m,
                yaw_rad,
            } => {
                let [x, y] = frame.to_world(position_m);
                Some([x, y, frame.yaw_to_world(yaw_rad)])
            }
            SetpointTarget::Velocity {
                velocity_m_s,
                yaw_rad,
            } if position_gain > 0.0 => {
                let [vx, vy] = frame.rotate_to_world(velocity_m_s);
                let lead_s = 1.0 / position_gain;
                Some([
                    here[0] + vx * lead_s,
                    here[1] + vy * lead_s,
                    frame.yaw_to_world(yaw_rad),
                ])
            }
            SetpointTarget::Velocity { .. } => None,
        });
        match target {
            Some(t) => {
                self.stale_hold = None;
                t
            }
            None => {
                self.counters.stale_steps = self.counters.stale_steps.saturating_add(1);
                *self.stale_hold.get_or_insert([here[0], here[1], e.yaw_rad])
            }
        }
    }
}

fn setpoint_is_finite(sp: &CompanionSetpoint) -> bool {
    let (a, b, yaw) = match sp.target {
        SetpointTarget::Position {
            position_m,
            yaw_rad,
        } => (position_m[0], position_m[1], yaw_rad),
        SetpointTarget::Velocity {
            velocity_m_s,
            yaw_rad,
        } => (velocity_m_s[0], velocity_m_s[1], yaw_rad),
    };
    a.is_finite() && b.is_finite() && yaw.is_finite() && sp.t_s.is_finite()
}

/// The mission's mode change from a mission mode (or the take-off hold), given the facts and
/// the voltage failsafe; the failsafe to raise with it, if any. `None`: stay.
pub fn transition(
    mode: FlightMode,
    m: &MissionStatus,
    battery_low: bool,
) -> Option<(FlightMode, Option<FailsafeReason>)> {
    use FlightMode::{Explore, Hold, Land, Return};
    let low = Some(FailsafeReason::BatteryLow);
    match mode {
        Hold if m.start_requested => Some((Explore, None)),
        Explore | Return if m.companion_silent => Some((Land, Some(FailsafeReason::CompanionLost))),
        Explore | Return if m.land_requested => Some((Land, Some(FailsafeReason::NoProgress))),
        Explore => match (m.energy, battery_low) {
            (Energy::Short, _) | (Energy::Unknown, true) => Some((Land, low)),
            (Energy::TurnBack | Energy::Plenty, true) => Some((Return, low)),
            (Energy::TurnBack, false) => Some((Return, None)),
            _ if m.explore_over => Some((Return, None)),
            _ => None,
        },
        Return if battery_low && matches!(m.energy, Energy::Short | Energy::Unknown) => {
            Some((Land, low))
        }
        Return if m.at_home => Some((Land, None)),
        _ => None,
    }
}
