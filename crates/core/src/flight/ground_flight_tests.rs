//! Ground-station commands flown closed-loop on the test vehicle: the remote kill, a flight
//! from the ground station alone, its manual takeover and the link-lost failsafe.

use super::test_vehicle::AIRFRAME;
use super::tests::{config, Flight, DT, HZ};
use crate::msgs::{
    CommandResult, FailsafeReason, FlightMode, GroundCommand, GroundMode, GroundSticks,
    MotorCommands, Outputs,
};

/// One control step with `command` from the ground station (and its heartbeat), at `dt`.
fn step(f: &mut Flight, command: GroundCommand, dt: f32) -> Outputs {
    f.step += 1;
    let mut inputs = f.veh.sense(f.step, HZ);
    inputs.ground.command = Some(command);
    inputs.ground.heartbeat = true;
    f.out = f.ap.step(&inputs, dt);
    f.veh.advance(&f.out.motors, DT);
    f.out
}

fn accepted(out: &Outputs) -> bool {
    out.ground_ack
        .is_some_and(|a| a.result == CommandResult::Accepted)
}

/// Flies `secs` with a ground heartbeat every step while `heartbeat`.
fn fly_linked(f: &mut Flight, secs: f32, heartbeat: bool) {
    f.fly_with(secs, |i, _| i.ground.heartbeat = heartbeat, |_, _| {});
}

#[test]
fn the_remote_kill_stops_the_motors_at_the_step_that_receives_it() {
    let mut f = Flight::new(config(), 11);
    f.take_off();
    f.fly(1.0);
    assert!(f.out.motors.throttle_norm.iter().all(|m| *m > 0.1));
    let out = step(&mut f, GroundCommand::Terminate, DT);
    assert!(accepted(&out));
    assert_eq!(out.motors, MotorCommands::STOPPED);
    assert_eq!(out.mode, FlightMode::Killed);
    // Latched: the radio's arm switch is still on, and the motors stay off all the way down.
    f.fly_with(
        2.0,
        |_, _| {},
        |o, _| assert_eq!(o.motors, MotorCommands::STOPPED),
    );
    assert_eq!(f.veh.position_m.z, 0.0);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::KillSwitch));

    // Received on a step whose dt is unusable: that step already stops them.
    let mut f = Flight::new(config(), 12);
    f.take_off();
    let out = step(&mut f, GroundCommand::Terminate, f32::NAN);
    assert!(accepted(&out));
    assert_eq!(out.motors, MotorCommands::STOPPED);
    f.fly(0.5);
    assert_eq!(f.out.mode, FlightMode::Killed);
    assert_eq!(f.out.motors, MotorCommands::STOPPED);
    // Any other command on such a step is refused for the ground station to repeat.
    let out = step(&mut f, GroundCommand::Land, 0.0);
    assert!(out
        .ground_ack
        .is_some_and(|a| a.result != CommandResult::Accepted));
}

#[test]
fn a_ground_station_alone_flies_a_takeoff_to_its_height_and_a_landing() {
    let mut f = Flight::new(config(), 13);
    fly_linked(&mut f, 0.2, true);
    let takeoff = GroundCommand::Takeoff {
        height_m: Some(1.5),
    };
    assert!(accepted(&step(&mut f, takeoff, DT)));
    fly_linked(&mut f, 7.0, true);
    assert_eq!(f.out.mode, FlightMode::Hold, "{:?}", f.ap.events());
    assert!(
        (f.veh.position_m.z - 1.5).abs() < 0.1,
        "{}",
        f.veh.position_m.z
    );
    let lower = GroundCommand::Takeoff {
        height_m: Some(0.8),
    };
    assert!(accepted(&step(&mut f, lower, DT)));
    fly_linked(&mut f, 4.0, true);
    assert!(
        (f.veh.position_m.z - 0.8).abs() < 0.1,
        "{}",
        f.veh.position_m.z
    );
    assert!(f.horizontal_error_m() < 0.1);
    assert!(accepted(&step(&mut f, GroundCommand::Land, DT)));
    fly_linked(&mut f, 6.0, true);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    assert_eq!(f.out.motors, MotorCommands::STOPPED);
    assert_eq!(f.veh.position_m.z, 0.0);
}

#[test]
fn a_manual_takeover_flies_the_ground_sticks() {
    let mut f = Flight::new(config(), 14);
    f.take_off();
    let hover = AIRFRAME.hover_collective();
    let sticks = |throttle_norm| {
        GroundCommand::Sticks(GroundSticks {
            throttle_norm,
            ..GroundSticks::default()
        })
    };
    step(&mut f, sticks(hover), DT);
    assert!(accepted(&step(
        &mut f,
        GroundCommand::SetMode(GroundMode::Manual),
        DT
    )));
    assert_eq!(f.out.mode, FlightMode::Manual);
    // Full-ish throttle climbs, as the radio's manual mode would.
    let z0 = f.veh.position_m.z;
    for _ in 0..(0.3 * HZ as f32) as usize {
        step(&mut f, sticks(0.9), DT);
    }
    assert_eq!(f.out.mode, FlightMode::Manual);
    assert!(f.veh.velocity_m_s.z > 0.5 && f.veh.position_m.z > z0);
    // Handed back: it holds where it is.
    step(&mut f, sticks(hover), DT);
    assert!(accepted(&step(
        &mut f,
        GroundCommand::SetMode(GroundMode::Hold),
        DT
    )));
    let hold_z = f.ap.last_outputs().setpoint.map(|s| s.position_m[2]);
    // It climbed well above the hold height in the takeover: back down in a few seconds.
    fly_linked(&mut f, 6.0, true);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert!(hold_z.is_some_and(|z| (f.veh.position_m.z - z).abs() < 0.1));
}

#[test]
fn a_lost_link_holds_in_place_then_lands() {
    let mut f = Flight::new(config(), 15);
    fly_linked(&mut f, 0.2, true);
    assert!(accepted(&step(&mut f, GroundCommand::Arm, DT)));
    fly_linked(&mut f, 6.0, true);
    assert_eq!(f.out.mode, FlightMode::Hold);
    let link = config().supervisor.link;
    fly_linked(&mut f, link.link_timeout_s + 0.1, false);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::LinkLost));
    fly_linked(&mut f, link.link_lost_land_s - 0.2, false);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert!(f.horizontal_error_m() < 0.1 && (f.veh.position_m.z - 1.0).abs() < 0.1);
    fly_linked(&mut f, 0.2, false);
    assert_eq!(f.out.mode, FlightMode::Land);
    fly_linked(&mut f, 6.0, false);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    assert_eq!(f.veh.position_m.z, 0.0);
}
