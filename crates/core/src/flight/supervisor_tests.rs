//! Tests of [`super`], kept apart so the module itself stays short.

use super::*;
use crate::msgs::{CommandResult, GroundCommand};

/// Drives a supervisor with a scripted world: a height, a battery, a lidar that can stop.
struct Script {
    sup: Supervisor,
    t_s: f64,
    pilot: PilotInput,
    height_m: f32,
    valid: bool,
    /// What the estimate knows horizontally while it is not valid.
    degraded: Horizontal,
    /// The companion asks to start exploring.
    start_explore: bool,
    lidar: bool,
    battery_v: f32,
    low_thrust: bool,
    /// A ground heartbeat arrives every step while true.
    heartbeat: bool,
    /// Sent with the next step only.
    command: Option<GroundCommand>,
    /// A companion computer is talking.
    companion: bool,
}

impl Script {
    fn new() -> Self {
        Self {
            sup: Supervisor::new(SupervisorConfig::default()),
            t_s: 0.0,
            pilot: PilotInput::default(),
            height_m: 0.0,
            valid: true,
            degraded: Horizontal::Unknown,
            start_explore: false,
            lidar: true,
            battery_v: 12.0,
            low_thrust: false,
            heartbeat: false,
            command: None,
            companion: false,
        }
    }

    /// Runs for `secs` at 100 Hz (scans at 5 Hz) and returns the final mode.
    fn run(&mut self, secs: f64) -> FlightMode {
        let steps = (secs * 100.0).round() as usize;
        for _ in 0..steps {
            self.t_s += 0.01;
            let tick = (self.t_s * 100.0).round() as u64;
            let estimate = EstimatedState {
                position_m: [0.0, 0.0, self.height_m],
                valid: self.valid,
                ..Default::default()
            };
            self.sup.update(&Status {
                t_s: self.t_s,
                pilot: self.pilot,
                estimate,
                horizontal: if self.valid {
                    Horizontal::Known
                } else {
                    self.degraded
                },
                scan_accepted: self.lidar && tick.is_multiple_of(20),
                battery_v: Some(self.battery_v),
                low_thrust: self.low_thrust,
                mission: MissionStatus {
                    companion_present: self.companion,
                    start_requested: self.start_explore,
                    ..MissionStatus::default()
                },
                ground: GroundMessages {
                    command: self.command.take(),
                    heartbeat: self.heartbeat,
                },
            });
        }
        self.sup.mode()
    }

    /// Sends `c` in one step and returns the answer.
    fn send(&mut self, c: GroundCommand) -> CommandResult {
        self.command = Some(c);
        self.run(0.01);
        let ack = self.sup.ack().expect("every command is answered");
        // Compared by kind: a command carrying a NaN is not equal to itself.
        assert_eq!(
            core::mem::discriminant(&ack.command),
            core::mem::discriminant(&c)
        );
        ack.result
    }

    fn climb_to_hold(&mut self) {
        self.run(0.1);
        self.pilot.arm = true;
        assert_eq!(self.run(0.1), FlightMode::Takeoff);
        self.height_m = 1.0;
        assert_eq!(self.run(0.1), FlightMode::Hold);
    }
}

#[test]
fn a_normal_flight_goes_through_every_mode_and_logs_it() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.pilot.arm = false;
    assert_eq!(s.run(0.1), FlightMode::Land);
    // Still airborne: no disarm.
    assert_eq!(s.run(2.0), FlightMode::Land);
    s.height_m = 0.02;
    assert_eq!(s.run(0.3), FlightMode::Land);
    assert_eq!(s.run(0.5), FlightMode::Disarmed);
    let modes: [FlightMode; 4] = {
        let mut it = s.sup.events().iter().map(|e| match e.kind {
            EventKind::ModeChange { to, .. } => to,
            EventKind::Failsafe(_)
            | EventKind::AdaptiveFallback(_)
            | EventKind::EstimateDegraded(_) => FlightMode::Killed,
        });
        core::array::from_fn(|_| it.next().unwrap())
    };
    use FlightMode::*;
    assert_eq!(modes, [Takeoff, Hold, Land, Disarmed]);
    assert_eq!(s.sup.failsafe(), None);
}

#[test]
fn landing_on_low_thrust_disarms_even_with_a_wrong_height() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.pilot.arm = false;
    assert_eq!(s.run(0.1), FlightMode::Land);
    // The estimate insists on 1 m, but the controller has been at its low limit for 1 s.
    s.low_thrust = true;
    assert_eq!(s.run(0.9), FlightMode::Land);
    assert_eq!(s.run(0.2), FlightMode::Disarmed);
}

#[test]
fn powering_up_with_the_arm_switch_on_does_not_take_off() {
    let mut s = Script::new();
    s.pilot.arm = true;
    assert_eq!(s.run(1.0), FlightMode::Disarmed);
    s.pilot.arm = false;
    s.run(0.1);
    s.pilot.arm = true;
    assert_eq!(s.run(0.1), FlightMode::Takeoff);
}

#[test]
fn kill_switch_stops_everything_and_needs_a_fresh_arming() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.pilot.kill = true;
    assert_eq!(s.run(0.01), FlightMode::Killed);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::KillSwitch));
    s.pilot.kill = false;
    s.height_m = 0.0;
    // Arm still on: stays killed.
    assert_eq!(s.run(1.0), FlightMode::Killed);
    s.pilot.arm = false;
    assert_eq!(s.run(0.1), FlightMode::Disarmed);
    s.pilot.arm = true;
    assert_eq!(s.run(0.1), FlightMode::Takeoff);
    assert_eq!(s.sup.failsafe(), None);
}

#[test]
fn lidar_lost_holds_for_a_bounded_time_then_lands() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.lidar = false;
    assert_eq!(s.run(1.5), FlightMode::Hold);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::LidarLost));
    // Back within the hold time: the failsafe clears.
    s.lidar = true;
    assert_eq!(s.run(0.5), FlightMode::Hold);
    assert_eq!(s.sup.failsafe(), None);
    s.lidar = false;
    assert_eq!(s.run(1.7), FlightMode::Hold);
    assert_eq!(s.run(0.6), FlightMode::Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::LidarLost));
}

#[test]
fn invalid_estimate_lands() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.valid = false;
    assert_eq!(s.run(0.01), FlightMode::Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::EstimateInvalid));
}

/// Known across x only (a corridor along y), within the degraded bounds or not.
fn across_x(flyable: bool) -> Horizontal {
    Horizontal::Across(crate::estimate::validity::AcrossOnly {
        across_axis: [1.0, 0.0],
        across_std_m: 0.03,
        along_std_m: 2.0,
        along_velocity_std_m_s: if flyable { 0.3 } else { 0.8 },
        flyable,
    })
}

#[test]
fn an_estimate_known_across_one_axis_carries_a_mission_leg_only_within_its_bounds() {
    let mut s = Script::new();
    s.companion = true;
    s.climb_to_hold();
    s.start_explore = true;
    assert_eq!(s.run(0.1), FlightMode::Explore);
    s.start_explore = false;
    s.valid = false;
    s.degraded = across_x(true);
    assert_eq!(s.run(1.0), FlightMode::Explore);
    assert_eq!(s.sup.failsafe(), None);
    let degraded = |s: &Script| {
        let mut kinds = s.sup.events().iter().filter_map(|e| match e.kind {
            EventKind::EstimateDegraded(on) => Some(on),
            _ => None,
        });
        [kinds.next(), kinds.next(), kinds.next()]
    };
    assert_eq!(degraded(&s), [Some(true), None, None]);
    // Both axes back: logged, and nothing else changes.
    s.valid = true;
    assert_eq!(s.run(0.1), FlightMode::Explore);
    assert_eq!(degraded(&s), [Some(true), Some(false), None]);
    // Past the degraded bounds (the along-axis velocity): the failsafe lands, as always.
    s.valid = false;
    s.degraded = across_x(false);
    assert_eq!(s.run(0.01), FlightMode::Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::EstimateInvalid));
}

#[test]
fn a_hold_does_not_fly_on_an_estimate_known_across_one_axis() {
    // Outside a mission leg nothing keeps the vehicle clear of the walls but the hold point,
    // which needs both axes.
    let mut s = Script::new();
    s.climb_to_hold();
    s.valid = false;
    s.degraded = across_x(true);
    assert_eq!(s.run(0.01), FlightMode::Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::EstimateInvalid));
}

#[test]
fn low_battery_lands_after_the_debounce_and_a_sag_does_not() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.battery_v = 10.3;
    assert_eq!(s.run(0.5), FlightMode::Hold);
    s.battery_v = 11.0;
    assert_eq!(s.run(1.0), FlightMode::Hold);
    s.battery_v = 10.3;
    assert_eq!(s.run(1.1), FlightMode::Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::BatteryLow));
    // Sagging further while landing: critical.
    s.battery_v = 9.5;
    s.run(1.1);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::BatteryCritical));
}

#[test]
fn critical_battery_prevents_arming() {
    let mut s = Script::new();
    s.battery_v = 9.0;
    s.run(2.0);
    s.pilot.arm = true;
    assert_eq!(s.run(0.1), FlightMode::Disarmed);
}

#[test]
fn manual_takeover_and_hand_back() {
    let mut s = Script::new();
    s.climb_to_hold();
    s.pilot.manual = true;
    assert_eq!(s.run(0.01), FlightMode::Manual);
    // Failsafes do not override the safety pilot.
    s.valid = false;
    assert_eq!(s.run(1.0), FlightMode::Manual);
    s.valid = true;
    s.pilot.manual = false;
    assert_eq!(s.run(0.01), FlightMode::Hold);
}

#[path = "ground_tests.rs"]
mod ground;
