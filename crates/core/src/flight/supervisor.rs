//! Modes and failsafes: which mode the vehicle is in and why, decided from the pilot's switches,
//! the estimate, the scan matcher's health and the battery.
//!
//! disarmed -> takeoff -> hold -> land -> disarmed, or on a mission takeoff -> hold -> explore
//! -> return -> land ([`super::mission`]), with manual (stick) flight reachable from any
//! flying mode through the takeover switch and the kill switch overriding everything (seed 002
//! sec. III). Failsafes only override the autonomous modes; a safety pilot in manual stays in
//! charge. Every mode change and failsafe goes to the event log.

use super::events::{EventKind, EventLog};
use super::mission::{self, MissionStatus};
use crate::msgs::{EstimatedState, FailsafeReason, FlightMode, PilotInput};

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
        }
    }
}

/// What the supervisor looks at each step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    pub t_s: f64,
    pub pilot: PilotInput,
    pub estimate: EstimatedState,
    /// A scan match was accepted by the estimator this step.
    pub scan_accepted: bool,
    /// A finite battery reading arrived this step.
    pub battery_v: Option<f32>,
    /// The controller asked for far less thrust than hover on the previous step.
    pub low_thrust: bool,
    /// The exploration mission's facts (all false without a companion).
    pub mission: MissionStatus,
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

    /// Logs what another part of the autopilot reports (the controller's fallbacks), beside
    /// the mode changes and failsafes.
    pub fn record(&mut self, t_s: f64, kind: EventKind) {
        self.events.push(t_s, kind);
    }

    /// One decision. Returns the mode to fly this step.
    pub fn update(&mut self, s: &Status) -> FlightMode {
        // SAFETY-CRITICAL: the kill switch wins over every other input and every mode.
        if s.pilot.kill {
            if self.mode != FlightMode::Killed {
                self.raise(s.t_s, FailsafeReason::KillSwitch);
                self.set_mode(s.t_s, FlightMode::Killed);
            }
            return self.mode;
        }
        // SAFETY-CRITICAL: leaving "killed" needs the arm switch off, then a fresh arming.
        if self.mode == FlightMode::Killed {
            if s.pilot.arm {
                return self.mode;
            }
            self.set_mode(s.t_s, FlightMode::Disarmed);
        }
        if !s.pilot.arm {
            self.arm_seen_off = true;
        }
        if s.scan_accepted {
            self.last_scan_t_s = s.t_s;
        }
        self.track_battery(s);

        match self.mode {
            FlightMode::Disarmed => self.maybe_arm(s),
            FlightMode::Manual => {
                if !s.pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Land);
                } else if !s.pilot.manual {
                    let next = if s.estimate.valid {
                        FlightMode::Hold
                    } else {
                        FlightMode::Land
                    };
                    self.set_mode(s.t_s, next);
                }
            }
            FlightMode::Takeoff | FlightMode::Hold | FlightMode::Explore | FlightMode::Return => {
                if s.pilot.manual {
                    self.set_mode(s.t_s, FlightMode::Manual);
                } else if self.autonomous_failsafes(s) || !s.pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Land);
                } else if self.mode == FlightMode::Takeoff
                    && s.estimate.position_m[2]
                        >= self.config.takeoff_height_m - self.config.takeoff_tolerance_m
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
                if s.pilot.manual && s.pilot.arm {
                    self.set_mode(s.t_s, FlightMode::Manual);
                } else {
                    self.landing_checks(s);
                }
            }
            FlightMode::Killed => {}
        }
        self.mode
    }

    fn maybe_arm(&mut self, s: &Status) {
        let ready = s.pilot.arm && self.arm_seen_off && !self.battery_critical;
        if !ready {
            return;
        }
        let next = if s.pilot.manual {
            FlightMode::Manual
        } else if s.estimate.valid {
            FlightMode::Takeoff
        } else {
            return;
        };
        self.arm_seen_off = false;
        self.failsafe = None;
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
        if !s.estimate.valid {
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
        if silent_s > self.config.lidar_timeout_s {
            self.raise(s.t_s, FailsafeReason::LidarLost);
            return silent_s > self.config.lidar_timeout_s + self.config.lidar_hold_s;
        }
        if self.failsafe == Some(FailsafeReason::LidarLost) {
            // The lidar is back within the hold time: the failsafe clears.
            self.failsafe = None;
        }
        false
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

#[cfg(test)]
#[path = "supervisor_tests.rs"]
mod tests;
