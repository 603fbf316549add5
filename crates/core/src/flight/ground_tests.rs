//! Ground commands and the link-lost failsafe, mode by mode, on the scripted supervisor.

use super::Script;
use crate::flight::events::EventKind;
use crate::msgs::{
    CommandResult, FailsafeReason, FlightMode, GroundCommand, GroundMode, GroundSticks, Refusal,
};
use CommandResult::{Accepted, InvalidParameter, Refused};
use FlightMode::*;
use GroundCommand as G;

/// Armed and holding at 1 m from a ground command alone, with the radio's switches all off.
fn ground_hold() -> Script {
    let mut s = Script::new();
    s.heartbeat = true;
    s.run(0.1);
    assert_eq!(s.send(G::Arm), Accepted);
    assert_eq!(s.sup.mode(), Takeoff);
    s.height_m = 1.0;
    assert_eq!(s.run(0.1), Hold);
    s
}

fn sticks(throttle_norm: f32) -> G {
    G::Sticks(GroundSticks {
        throttle_norm,
        ..GroundSticks::default()
    })
}

#[test]
fn a_ground_station_alone_arms_lands_and_disarms() {
    let mut s = ground_hold();
    // The radio's arm switch, off all along, does not land it: only a flip would.
    assert_eq!(s.run(2.0), Hold);
    assert_eq!(s.send(G::Arm), Accepted);
    assert_eq!(s.send(G::Disarm), Refused(Refusal::Airborne));
    assert_eq!(s.sup.mode(), Hold);
    assert_eq!(s.send(G::Land), Accepted);
    assert_eq!(s.sup.mode(), Land);
    assert_eq!(s.send(G::Arm), Refused(Refusal::WrongMode));
    s.height_m = 0.02;
    assert_eq!(s.run(1.0), Disarmed);
    // Landed and disarmed: no re-arming by itself, a new command arms.
    assert_eq!(s.run(1.0), Disarmed);
    assert_eq!(s.send(G::Land), Refused(Refusal::WrongMode));
    assert_eq!(s.send(G::Disarm), Accepted);
    assert_eq!(s.send(G::Arm), Accepted);
    assert_eq!(s.sup.mode(), Takeoff);
    // Still on the floor: a disarm is taken at once.
    assert_eq!(s.send(G::Disarm), Accepted);
    assert_eq!(s.sup.mode(), Disarmed);
}

#[test]
fn arming_is_refused_without_an_estimate_or_with_a_critical_battery() {
    let mut s = Script::new();
    s.valid = false;
    assert_eq!(s.send(G::Arm), Refused(Refusal::EstimateInvalid));
    s.valid = true;
    s.battery_v = 9.0;
    s.run(1.5);
    assert_eq!(s.send(G::Arm), Refused(Refusal::BatteryCritical));
    let takeoff = G::Takeoff { height_m: None };
    assert_eq!(s.send(takeoff), Refused(Refusal::BatteryCritical));
    assert_eq!(s.sup.mode(), Disarmed);
}

#[test]
fn takeoff_heights_are_bounded_and_move_the_hold() {
    let mut s = Script::new();
    for bad in [0.1, 3.5, f32::NAN, f32::INFINITY, -1.0] {
        let c = G::Takeoff {
            height_m: Some(bad),
        };
        assert_eq!(s.send(c), InvalidParameter, "{bad}");
        assert_eq!(s.sup.mode(), Disarmed);
    }
    assert_eq!(
        s.send(G::Takeoff {
            height_m: Some(2.0)
        }),
        Accepted
    );
    assert_eq!((s.sup.mode(), s.sup.hold_height_m()), (Takeoff, 2.0));
    // The configured 1 m is not the target any more.
    s.height_m = 1.0;
    assert_eq!(s.run(0.1), Takeoff);
    s.height_m = 2.0;
    assert_eq!(s.run(0.1), Hold);
    assert_eq!(
        s.send(G::Takeoff {
            height_m: Some(1.5)
        }),
        Accepted
    );
    assert_eq!((s.sup.mode(), s.sup.hold_height_m()), (Hold, 1.5));
    assert_eq!(s.send(G::Land), Accepted);
    let c = G::Takeoff { height_m: None };
    assert_eq!(s.send(c), Refused(Refusal::WrongMode));
    // The next arming by the radio flies the configured height again.
    s.height_m = 0.0;
    s.run(1.0);
    s.pilot.arm = true;
    s.run(0.1);
    assert_eq!((s.sup.mode(), s.sup.hold_height_m()), (Takeoff, 1.0));
}

#[test]
fn terminate_kills_at_once_latches_and_only_a_ground_disarm_releases_it() {
    let mut s = Script::new();
    s.climb_to_hold();
    assert_eq!(s.send(G::Terminate), Accepted);
    assert_eq!(s.sup.mode(), Killed);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::KillSwitch));
    // Radio switches do not release it: arm off and on again, manual on.
    s.pilot.arm = false;
    assert_eq!(s.run(0.5), Killed);
    s.pilot.arm = true;
    s.pilot.manual = true;
    assert_eq!(s.run(0.5), Killed);
    assert_eq!(s.send(G::Arm), Refused(Refusal::Killed));
    assert_eq!(
        s.send(G::SetMode(GroundMode::Hold)),
        Refused(Refusal::Killed)
    );
    // With the radio's kill switch on, the ground cannot release it either.
    s.pilot.kill = true;
    assert_eq!(s.send(G::Disarm), Refused(Refusal::RadioInCharge));
    s.pilot.kill = false;
    assert_eq!(s.send(G::Disarm), Accepted);
    assert_eq!(s.sup.mode(), Disarmed);
    assert_eq!(s.run(0.5), Disarmed);
}

#[test]
fn the_radio_keeps_priority() {
    let mut s = ground_hold();
    // The radio's manual switch takes over; the ground's mode commands are refused meanwhile.
    s.pilot.arm = true;
    s.pilot.manual = true;
    assert_eq!(s.run(0.1), Manual);
    assert_eq!(
        s.send(G::SetMode(GroundMode::Hold)),
        Refused(Refusal::RadioInCharge)
    );
    assert_eq!(s.send(G::Land), Refused(Refusal::RadioInCharge));
    assert_eq!(s.sup.mode(), Manual);
    s.pilot.manual = false;
    assert_eq!(s.run(0.1), Hold);
    // A ground arm does not undo the radio's arm switch flipped off: it lands.
    s.pilot.arm = false;
    assert_eq!(s.run(0.1), Land);
    // A ground disarm on the floor leaves the radio's manual switch in force for its arming.
    s.height_m = 0.0;
    s.run(1.0);
    s.pilot.manual = true;
    s.run(0.1);
    assert_eq!(s.send(G::Disarm), Accepted);
    s.pilot.arm = true;
    assert_eq!(s.run(0.1), Manual);
    // The radio's kill switch beats a ground station that keeps sending.
    let mut s = ground_hold();
    s.pilot.kill = true;
    assert_eq!(s.send(G::Arm), Refused(Refusal::Killed));
    assert_eq!(s.sup.mode(), Killed);
}

#[test]
fn manual_takeover_needs_fresh_sticks_and_ends_when_they_stop() {
    let mut s = ground_hold();
    let manual = G::SetMode(GroundMode::Manual);
    assert_eq!(s.send(manual), Refused(Refusal::NoSticks));
    assert_eq!(s.send(sticks(1.5)), InvalidParameter);
    assert_eq!(s.send(sticks(f32::NAN)), InvalidParameter);
    assert_eq!(s.send(manual), Refused(Refusal::NoSticks));
    assert_eq!(s.send(sticks(0.55)), Accepted);
    assert_eq!(s.send(manual), Accepted);
    assert_eq!(s.sup.mode(), Manual);
    assert_eq!(s.sup.pilot().throttle_norm, 0.55);
    // Sticks keep coming: manual stays; a hold command hands back.
    for _ in 0..30 {
        assert_eq!(s.send(sticks(0.6)), Accepted);
    }
    assert_eq!(s.sup.mode(), Manual);
    assert_eq!(s.send(G::SetMode(GroundMode::Hold)), Accepted);
    assert_eq!(s.sup.mode(), Hold);
    // Again, then the sticks stop: the hand-back holds and says why.
    s.send(sticks(0.55));
    assert_eq!(s.send(manual), Accepted);
    assert_eq!(s.run(0.4), Manual);
    assert_eq!(s.run(0.2), Hold);
    // The link itself is alive, so the failsafe does not stay in force: the log says it.
    let lost = EventKind::Failsafe(FailsafeReason::LinkLost);
    assert_eq!(s.sup.events().iter().filter(|e| e.kind == lost).count(), 1);
    // Manual is not a way to take off.
    let mut d = Script::new();
    d.send(sticks(0.5));
    assert_eq!(d.send(manual), Refused(Refusal::WrongMode));
}

#[test]
fn exploring_and_returning_need_a_companion() {
    let mut s = ground_hold();
    let explore = G::SetMode(GroundMode::Explore);
    assert_eq!(s.send(explore), Refused(Refusal::NoCompanion));
    assert_eq!(s.send(G::Return), Refused(Refusal::NoCompanion));
    s.companion = true;
    assert_eq!(s.send(explore), Accepted);
    assert_eq!(s.sup.mode(), Explore);
    assert_eq!(s.send(G::Return), Accepted);
    assert_eq!(s.sup.mode(), Return);
    assert_eq!(s.send(explore), Refused(Refusal::WrongMode));
    assert_eq!(s.send(G::SetMode(GroundMode::Hold)), Accepted);
    assert_eq!(s.sup.mode(), Hold);
    assert_eq!(s.send(G::Return), Accepted);
    assert_eq!(s.send(G::Land), Accepted);
    assert_eq!(s.sup.mode(), Land);
    assert_eq!(s.send(explore), Refused(Refusal::WrongMode));
    // Not before the take-off hold is reached.
    let mut t = Script::new();
    t.companion = true;
    t.send(G::Arm);
    assert_eq!(t.send(explore), Refused(Refusal::WrongMode));
}

#[test]
fn a_lost_link_holds_then_lands_and_a_returning_link_clears_it() {
    let mut s = ground_hold();
    s.companion = true;
    s.send(G::SetMode(GroundMode::Explore));
    s.heartbeat = false;
    assert_eq!(s.run(2.9), Explore);
    assert_eq!(s.run(0.2), Hold);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::LinkLost));
    // Back within the hold time: the failsafe clears, the vehicle keeps holding.
    s.heartbeat = true;
    assert_eq!(s.run(0.1), Hold);
    assert_eq!(s.sup.failsafe(), None);
    assert_eq!(s.run(5.0), Hold);
    // Lost for good: hold for `link_lost_land_s`, then land.
    s.heartbeat = false;
    assert_eq!(s.run(3.1), Hold);
    assert_eq!(s.run(9.8), Hold);
    assert_eq!(s.run(0.2), Land);
    assert_eq!(s.sup.failsafe(), Some(FailsafeReason::LinkLost));
}

#[test]
fn a_ground_station_never_heard_never_triggers_the_failsafe() {
    let mut s = Script::new();
    s.climb_to_hold();
    assert_eq!(s.run(30.0), Hold);
    assert_eq!(s.sup.failsafe(), None);
    // One that left while the vehicle stood disarmed is forgotten.
    let mut s = Script::new();
    s.heartbeat = true;
    s.run(1.0);
    s.heartbeat = false;
    s.run(5.0);
    s.climb_to_hold();
    assert_eq!(s.run(30.0), Hold);
    assert_eq!(s.sup.failsafe(), None);
}
