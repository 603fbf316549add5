//! Modes and failsafes: which mode the vehicle is in and why, decided from the pilot's switches,
//! the ground station's commands, the estimate, the scan matcher's health and the battery.
//!
//! disarmed -> takeoff -> hold -> land -> disarmed, or on a mission takeoff -> hold -> explore
//! -> return -> land ([`super::mission`]), with manual (stick) flight reachable from any
//! flying mode through the takeover switch and the kill switch overriding everything (seed 002
//! sec. III). Failsafes only override the autonomous modes; a safety pilot in manual stays in
//! charge. Every mode change and failsafe goes to the event log. How the ground station's
//! commands and the radio share the switches is in [`super::ground`]; what each command does
//! in each mode is in `ground_commands.rs`.

use super::events::{EventKind, EventLog};
use super::ground::{GroundLink, GroundLinkConfig};
use super::mission::{self, MissionStatus};
use crate::estimate::validity::Horizontal;
use crate::msgs::{
    EstimatedState, FailsafeReason, FlightMode, GroundAck, GroundMessages, PilotInput, Refusal,
};

/// Failsafe thresholds and mode-transition tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupervisorConfig {
    /// No accepted scan match for this long (s) raises "lidar lost"; holding continues on the IMU.
    pub lidar_timeout_s: f32,
    /// After "lidar lost", hold on the IMU this much longer (s), then land. Short: it rides out
    /// a lidar that comes back, but the IMU-only hold strays (0.11 m 2 s after the last scan,
    /// 0.20 m after 3 s, 0.35 m after 4 s, mean of 20 simulated seeds), and with 3 s here plus a
    /// 0.5 m/s landing the simulated vehicle reached the walls of a small room in 4 to 8 of 20.
    pub lidar_hold_s: f32,
    /// Pack voltage below which the vehicle lands (V); default 3.5 V per cell of a 3S pack.
    pub battery_low_v: f32,
    /// Pack voltage below which it lands at once, faster (V); 3.3 V per cell.
    pub battery_critical_v: f32,
    /// A voltage must stay below a threshold this long (s) to count: load sags are brief.
    pub battery_debounce_s: f32,
    /// Hold height above the takeoff point (m) and how close counts as reached.
    pub takeoff_height_m: f32,
    pub takeoff_tolerance_m: f32,
    /// Touchdown: below this height (m), slower than this (m/s), for this long (s).
    pub touchdown_height_m: f32,
    pub touchdown_speed_m_s: f32,
    pub touchdown_s: f32,
    /// Touchdown also when landing with thrust this long (s) at the controller's low limit:
    /// the floor is holding the vehicle up, whatever the estimate says (an IMU that aliased
    /// the touchdown shock can leave the filter believing it still moves).
    pub low_thrust_s: f32,
    /// The ground-station link: its loss, and the bounds of its commands.
    pub link: GroundLinkConfig,
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        Self {
            lidar_timeout_s: 1.0,
            lidar_hold_s: 1.0,
            battery_low_v: 10.5,
            battery_critical_v: 9.9,
            battery_debounce_s: 1.0,
            takeoff_height_m: 1.0,
            takeoff_tolerance_m: 0.05,
            touchdown_height_m: 0.1,
            touchdown_speed_m_s: 0.2,
            touchdown_s: 0.5,
            low_thrust_s: 1.0,
            link: GroundLinkConfig::default(),
        }
    }
}

/// What the supervisor looks at each step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    pub t_s: f64,
    pub pilot: PilotInput,
    pub estimate: EstimatedState,
    /// What the estimate still knows horizontally, axis by axis.
    pub horizontal: Horizontal,
    /// A scan match was accepted by the estimator this step.
    pub scan_accepted: bool,
    /// A finite battery reading arrived this step.
    pub battery_v: Option<f32>,
    /// The controller asked for far less thrust than hover on the previous step.
    pub low_thrust: bool,
    /// The exploration mission's facts (all false without a companion).
    pub mission: MissionStatus,
    /// What the ground station sent this step.
    pub ground: GroundMessages,
}

/// Capacity of the event log.
pub const EVENT_LOG_LEN: usize = 32;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supervisor {
    pub config: SupervisorConfig,
    mode: FlightMode,
    failsafe: Option<FailsafeReason>,
    /// The arm switch has been seen off since the last arming: arming needs an off-to-on edge,
    /// so a vehicle powered up with the switch on does not take off by itself.
    arm_seen_off: bool,
    last_scan_t_s: f64,
    low_since_t_s: Option<f64>,
    critical_since_t_s: Option<f64>,
    battery_low: bool,
    battery_critical: bool,
    touchdown_since_t_s: Option<f64>,
    low_thrust_since_t_s: Option<f64>,
    events: EventLog<EVENT_LOG_LEN>,
    link: GroundLink,
    /// The switches and sticks this step was decided on (the radio's merged with the ground's).
    pilot: PilotInput,
    /// The answer to this step's ground command.
    ack: Option<GroundAck>,
    /// Height (m) of the take-off and hold above the take-off floor for this flight.
    hold_height_m: f32,
    /// A take-off height a ground command asked for, taken up at the arming it causes.
    takeoff_height_request_m: Option<f32>,
    /// A mission leg is flying on an estimate known across one axis only.
    degraded: bool,
}

impl Supervisor {
    pub fn new(config: SupervisorConfig) -> Self {
        Self {
            config,
            mode: FlightMode::Disarmed,
            failsafe: None,
            arm_seen_off: false,
            last_scan_t_s: 0.0,
            low_since_t_s: None,
            critical_since_t_s: None,
            battery_low: false,
            battery_critical: false,
            touchdown_since_t_s: None,
            low_thrust_since_t_s: None,
            events: EventLog::default(),
            link: GroundLink::new(config.link),
            pilot: PilotInput::default(),
            ack: None,
            hold_height_m: config.takeoff_height_m,
            takeoff_height_request_m: None,
            degraded: false,
        }
    }

    pub fn mode(&self) -> FlightMode {
        self.mode
    }

    /// The most recent failsafe still in force.
    pub fn failsafe(&self) -> Option<FailsafeReason> {
        self.failsafe
    }

    pub fn events(&self) -> &EventLog<EVENT_LOG_LEN> {
        &self.events
    }

    /// The switches and sticks the last step flew on: the radio's, merged with the ground's.
    pub fn pilot(&self) -> &PilotInput {
        &self.pilot
    }

    /// The answer to the last step's ground command.
    pub fn ack(&self) -> Option<GroundAck> {
        self.ack
    }

    /// Take-off and hold height (m) of this flight.
    pub fn hold_height_m(&self) -> f32 {
        self.hold_height_m
    }

    /// No scan match accepted for longer than the lidar timeout, at `t_s`.
    pub fn lidar_silent(&self, t_s: f64) -> bool {
        (t_s - self.last_scan_t_s) as f32 > self.config.lidar_timeout_s
    }

    /// New thresholds and timings, keeping every timer and latch.
    pub fn retune(&mut self, config: SupervisorConfig) {
        self.config = config;
        self.link.config = config.link;
    }

    /// SAFETY-CRITICAL: a ground terminate, latched even on a step that cannot run.
    pub fn terminate(&mut self) {
        self.link.terminate();
    }

    /// The ground's terminate is latched.
    pub fn terminated(&self) -> bool {
        self.link.terminated()
    }

    /// Logs what another part of the autopilot reports (the controller's fallbacks), beside
    /// the mode changes and failsafes.
    pub fn record(&mut self, t_s: f64, kind: EventKind) {
        self.events.push(t_s, kind);
    }

    /// One decision. Returns the mode to fly this step.
    pub fn update(&mut self, s: &Status) -> FlightMode {
        self.link.observe(s.t_s, &s.pilot, &s.ground);
        let command = s.ground.command;
        self.ack = command.and_then(|c| self.kill_command(c));
        self.watch_ground_manual(s.t_s);
        let mut pilot = self.link.switches(&s.pilot);
        self.pilot = pilot;
        // SAFETY-CRITICAL: the kill switch wins over every other input and every mode.
        if pilot.kill {
            if self.mode != FlightMode::Killed {
                self.raise(s.t_s, FailsafeReason::KillSwitch);
                self.set_mode(s.t_s, FlightMode::Killed);
            }
            self.refuse_unanswered(command, Refusal::Killed);
            return self.mode;
        }
        // SAFETY-CRITICAL: leaving "killed" needs the arm switch off, then a fresh arming.
        if self.mode == FlightMode::Killed {
            if pilot.arm {
                self.refuse_unanswered(command, Refusal::Killed);
                return self.mode;
            }
            self.set_mode(s.t_s, FlightMode::Disarmed);
        }
        if !pilot.arm {
            self.arm_seen_off = true;
        }
        if s.scan_accepted {
            self.last_scan_t_s = s.t_s;
        }
        self.track_battery(s);
        if self.mode == FlightMode::Disarmed {
            self.link.forget_if_lost(s.t_s);
        }
        if let Some(c) = command.filter(|_| self.ack.is_none()) {
            let before = self.mode;
            let result = self.command(c, s);
            self.ack = Some(GroundAck { command: c, result });
            pilot = self.link.switches(&s.pilot);
            self.pilot = pilot;
            if self.mode != before {
                // The commanded mode flies from this step; its checks start with the next.
                return self.mode;
            }
        }

        match self.mode {
            FlightMode::Disarmed => self.maybe_arm(s, &pilot),
            FlightMode::Manual => {
                if !pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Land);
                } else if !pilot.manual {
                    let next = if s.estimate.valid {
                        FlightMode::Hold
                    } else {
                        FlightMode::Land
                    };
                    self.set_mode(s.t_s, next);
                }
            }
            FlightMode::Takeoff | FlightMode::Hold | FlightMode::Explore | FlightMode::Return => {
                if pilot.manual {
                    self.set_mode(s.t_s, FlightMode::Manual);
                } else if self.autonomous_failsafes(s) || !pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Land);
                } else if let Some(next) = self.link_lost(s.t_s) {
                    self.set_mode(s.t_s, next);
                } else if self.mode == FlightMode::Takeoff
                    && s.estimate.position_m[2]
                        >= self.hold_height_m - self.config.takeoff_tolerance_m
                {
                    self.set_mode(s.t_s, FlightMode::Hold);
                } else if let Some((next, reason)) =
                    mission::transition(self.mode, &s.mission, self.battery_low)
                {
                    if let Some(reason) = reason {
                        self.raise(s.t_s, reason);
                    }
                    self.set_mode(s.t_s, next);
                }
            }
            FlightMode::Land => {
                if pilot.manual && pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Manual);
                } else {
                    self.landing_checks(s);
                }
            }
            FlightMode::Killed => {}
        }
        self.mode
    }

    fn maybe_arm(&mut self, s: &Status, pilot: &PilotInput) {
        let ready = pilot.arm && self.arm_seen_off && !self.battery_critical;
        if !ready {
            return;
        }
        let next = if pilot.manual {
            FlightMode::Manual
        } else if s.estimate.valid {
            FlightMode::Takeoff
        } else {
            return;
        };
        self.arm_seen_off = false;
        self.failsafe = None;
        self.hold_height_m = self
            .takeoff_height_request_m
            .take()
            .unwrap_or(self.config.takeoff_height_m);
        // The lidar gets a full timeout from arming to report.
        self.last_scan_t_s = s.t_s;
        self.set_mode(s.t_s, next);
    }

    /// Checks the failsafes of the autonomous modes; true when the vehicle must land. "Lidar
    /// lost" alone keeps holding (on the IMU) until `lidar_hold_s` has passed.
    fn autonomous_failsafes(&mut self, s: &Status) -> bool {
        if self.battery_critical {
            self.raise(s.t_s, FailsafeReason::BatteryCritical);
            return true;
        }
        if !self.estimate_flyable(s) {
            self.raise(s.t_s, FailsafeReason::EstimateInvalid);
            return true;
        }
        // On a mission the battery decides between the way home and landing here (`mission`).
        let on_mission = matches!(self.mode, FlightMode::Explore | FlightMode::Return);
        if self.battery_low && !on_mission {
            self.raise(s.t_s, FailsafeReason::BatteryLow);
            return true;
        }
        let silent_s = (s.t_s - self.last_scan_t_s) as f32;
        if self.lidar_silent(s.t_s) {
            self.raise(s.t_s, FailsafeReason::LidarLost);
            return silent_s > self.config.lidar_timeout_s + self.config.lidar_hold_s;
        }
        if self.failsafe == Some(FailsafeReason::LidarLost) {
            // The lidar is back within the hold time: the failsafe clears.
            self.failsafe = None;
        }
        false
    }

    /// Whether the estimate carries this mode on. A valid estimate carries every mode. One
    /// known across a single horizontal axis, within the degraded bounds, carries a mission
    /// leg only (explore and return fly velocity setpoints that keep clear of the walls on the
    /// live scan; [`crate::estimate::validity`]); entering and leaving that degraded flight
    /// are logged. Anything else is the estimate-invalid failsafe, as always.
    fn estimate_flyable(&mut self, s: &Status) -> bool {
        let on_mission = matches!(self.mode, FlightMode::Explore | FlightMode::Return);
        let degraded = !s.estimate.valid && on_mission && s.horizontal.flyable_on_velocity();
        if degraded != self.degraded {
            self.degraded = degraded;
            self.events
                .push(s.t_s, EventKind::EstimateDegraded(degraded));
        }
        s.estimate.valid || degraded
    }

    /// The link-lost failsafe of the autonomous modes: hold, then land after
    /// `link_lost_land_s`; it clears when the heartbeats return (the vehicle keeps holding).
    fn link_lost(&mut self, t_s: f64) -> Option<FlightMode> {
        let Some(lost_s) = self.link.lost_for_s(t_s) else {
            if self.failsafe == Some(FailsafeReason::LinkLost) {
                self.failsafe = None;
            }
            return None;
        };
        // Another failsafe in force keeps its name (two alternating would flood the log).
        if self.failsafe.is_none() {
            self.raise(t_s, FailsafeReason::LinkLost);
        }
        Some(if lost_s > self.link.config.link_lost_land_s {
            FlightMode::Land
        } else {
            FlightMode::Hold
        })
    }

    /// A manual flight on the ground's sticks ends when they stop or the link is lost: the
    /// manual mode's hand-back then holds (or lands without a trustworthy estimate).
    fn watch_ground_manual(&mut self, t_s: f64) {
        let flying_ground_sticks = self.mode == FlightMode::Manual && self.link.ground_manual();
        if flying_ground_sticks
            && (self.link.lost_for_s(t_s).is_some() || !self.link.sticks_fresh(t_s))
        {
            self.raise(t_s, FailsafeReason::LinkLost);
            self.link.set_manual(false);
        }
    }

    fn landing_checks(&mut self, s: &Status) {
        if self.battery_critical {
            self.raise(s.t_s, FailsafeReason::BatteryCritical);
        }
        let c = self.config;
        let e = &s.estimate;
        let still_on_floor = e.position_m[2] < c.touchdown_height_m
            && libm::fabsf(e.velocity_m_s[2]) < c.touchdown_speed_m_s;
        let landed = held_for(
            &mut self.touchdown_since_t_s,
            still_on_floor,
            s.t_s,
            c.touchdown_s,
        ) | held_for(
            &mut self.low_thrust_since_t_s,
            s.low_thrust,
            s.t_s,
            c.low_thrust_s,
        );
        if landed {
            self.touchdown_since_t_s = None;
            self.low_thrust_since_t_s = None;
            // Down: the arm latch is the radio's switch again (a ground-armed flight is over).
            self.link.follow_radio_arm();
            self.set_mode(s.t_s, FlightMode::Disarmed);
        }
    }

    /// Debounced, latching low and critical battery flags (cleared only by a new arming cycle
    /// when the voltage has recovered, e.g. after a pack swap).
    fn track_battery(&mut self, s: &Status) {
        let Some(v) = s.battery_v else {
            return;
        };
        let c = self.config;
        let (t, debounce) = (s.t_s, c.battery_debounce_s);
        self.battery_low |= held_for(&mut self.low_since_t_s, v < c.battery_low_v, t, debounce);
        self.battery_critical |= held_for(
            &mut self.critical_since_t_s,
            v < c.battery_critical_v,
            t,
            debounce,
        );
        if self.mode == FlightMode::Disarmed && v >= self.config.battery_low_v {
            self.battery_low = false;
            self.battery_critical = false;
        }
    }

    fn raise(&mut self, t_s: f64, reason: FailsafeReason) {
        if self.failsafe != Some(reason) {
            self.failsafe = Some(reason);
            self.events.push(t_s, EventKind::Failsafe(reason));
        }
    }

    fn set_mode(&mut self, t_s: f64, to: FlightMode) {
        if to != self.mode {
            self.events.push(
                t_s,
                EventKind::ModeChange {
                    from: self.mode,
                    to,
                },
            );
            self.mode = to;
        }
    }
}

/// True once `condition` has held continuously for `secs`; `since` remembers when it began.
fn held_for(since: &mut Option<f64>, condition: bool, t_s: f64, secs: f32) -> bool {
    if !condition {
        *since = None;
        return false;
    }
    (t_s - *since.get_or_insert(t_s)) as f32 >= secs
}

#[path = "ground_commands.rs"]
mod ground_commands;
#[cfg(test)]
#[path = "supervisor_tests.rs"]
mod tests;
