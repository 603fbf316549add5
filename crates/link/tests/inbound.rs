//! Ground to vehicle: commands, targets, signing and replays, with frames made by the
//! `mavlink` crate's writer.
mod common;

use common::*;
use plumbline_core::msgs::{CommandResult, GroundCommand, GroundMode, Refusal};
use plumbline_link::common::{
    MavCmd, MavMessage, MavResult, COMMAND_LONG_DATA, MANUAL_CONTROL_DATA,
};
use plumbline_link::{InboundEvent, Link, LinkConfig, SigningKey};

fn command(cmd: MavCmd, param1: f32, param2: f32, param7: f32) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1,
        param2,
        param7,
        command: cmd,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    })
}

fn keyed() -> Link {
    Link::new(LinkConfig {
        key: Some(SigningKey {
            secret: KEY,
            link_id: 1,
        }),
        ..LinkConfig::default()
    })
}

fn commands(events: &[InboundEvent]) -> Vec<GroundCommand> {
    events
        .iter()
        .filter_map(|e| match e {
            InboundEvent::Command { command, .. } => Some(*command),
            _ => None,
        })
        .collect()
}

fn acks(bytes: &[u8]) -> Vec<(MavCmd, MavResult, u8)> {
    decode_all(bytes, None)
        .into_iter()
        .filter_map(|(_, m)| match m {
            MavMessage::COMMAND_ACK(a) => Some((a.command, a.result, a.target_system)),
            _ => None,
        })
        .collect()
}

#[test]
fn each_command_long_becomes_its_ground_command() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let cases = [
        (
            command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0, 0.0),
            GroundCommand::Arm,
        ),
        (
            command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0, 0.0, 0.0),
            GroundCommand::Disarm,
        ),
        (
            command(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, 1.5),
            GroundCommand::Takeoff {
                height_m: Some(1.5),
            },
        ),
        (
            command(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, f32::NAN),
            GroundCommand::Takeoff { height_m: None },
        ),
        (
            command(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0, 0.0),
            GroundCommand::Land,
        ),
        (
            command(MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0, 0.0, 0.0),
            GroundCommand::Return,
        ),
        (
            command(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 1.0, 0.0, 0.0),
            GroundCommand::Terminate,
        ),
        (
            command(MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 3.0, 0.0),
            GroundCommand::SetMode(GroundMode::Explore),
        ),
        (
            command(MavCmd::MAV_CMD_DO_SET_MODE, 129.0, 2.0, 0.0),
            GroundCommand::SetMode(GroundMode::Hold),
        ),
    ];
    for (message, expected) in cases {
        let (events, replies) = feed(&mut link, &ground.frame(&message), at(0.0));
        assert_eq!(commands(&events), [expected]);
        assert!(
            replies.is_empty(),
            "the autopilot, not the link, answers {expected:?}"
        );
    }
    assert_eq!(link.counters().refused(), 0);
}

#[test]
fn the_autopilots_answer_goes_back_as_command_ack() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let frame = ground.frame(&command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        1.0,
        0.0,
        0.0,
    ));
    let (events, _) = feed(&mut link, &frame, at(0.0));
    let Some(InboundEvent::Command { ack: Some(to), .. }) = events.first() else {
        panic!("{events:?}");
    };
    let mut out = Vec::new();
    for result in [
        CommandResult::Accepted,
        CommandResult::Refused(Refusal::WrongMode),
        CommandResult::InvalidParameter,
    ] {
        link.acknowledge(*to, result, at(0.0), &mut out);
    }
    let cmd = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
    assert_eq!(
        acks(&out),
        [
            (cmd, MavResult::MAV_RESULT_ACCEPTED, 255),
            (cmd, MavResult::MAV_RESULT_TEMPORARILY_REJECTED, 255),
            (cmd, MavResult::MAV_RESULT_DENIED, 255),
        ]
    );
}

#[test]
fn commands_nobody_can_carry_out_are_answered_by_the_link() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let mut bytes = Vec::new();
    // Not implemented; an unselectable mode (Killed); arm with a nonsense parameter; terminate
    // with param1 below 0.5; a custom-mode number without the custom-mode flag.
    bytes.extend(ground.frame(&command(MavCmd::MAV_CMD_DO_CHANGE_SPEED, 1.0, 0.0, 0.0)));
    bytes.extend(ground.frame(&command(MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 7.0, 0.0)));
    bytes.extend(ground.frame(&command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        0.5,
        0.0,
        0.0,
    )));
    bytes.extend(ground.frame(&command(
        MavCmd::MAV_CMD_DO_FLIGHTTERMINATION,
        0.0,
        0.0,
        0.0,
    )));
    bytes.extend(ground.frame(&command(MavCmd::MAV_CMD_DO_SET_MODE, 0.0, 2.0, 0.0)));
    let (events, replies) = feed(&mut link, &bytes, at(0.0));
    assert!(events.is_empty(), "{events:?}");
    let results: Vec<MavResult> = acks(&replies).into_iter().map(|a| a.1).collect();
    assert_eq!(
        results,
        [
            MavResult::MAV_RESULT_UNSUPPORTED,
            MavResult::MAV_RESULT_DENIED,
            MavResult::MAV_RESULT_DENIED,
            MavResult::MAV_RESULT_DENIED,
            MavResult::MAV_RESULT_DENIED,
        ]
    );
}

#[test]
fn manual_control_gives_sticks_and_an_invalid_axis_is_refused() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let sticks = |x, y, z, r| {
        MavMessage::MANUAL_CONTROL(MANUAL_CONTROL_DATA {
            x,
            y,
            z,
            r,
            target: 1,
            ..Default::default()
        })
    };
    let (events, _) = feed(
        &mut link,
        &ground.frame(&sticks(500, -1000, 250, 2000)),
        at(0.0),
    );
    let [GroundCommand::Sticks(s)] = commands(&events)[..] else {
        panic!("{events:?}");
    };
    assert_eq!(
        (s.pitch_norm, s.roll_norm, s.throttle_norm, s.yaw_norm),
        (0.5, -1.0, 0.25, 1.0)
    );
    let (events, _) = feed(
        &mut link,
        &ground.frame(&sticks(0, 0, i16::MAX, 0)),
        at(0.0),
    );
    assert!(events.is_empty());
    assert_eq!(link.counters().malformed, 1);
}

#[test]
fn other_systems_and_components_are_not_obeyed() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let mut land = command(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0, 0.0);
    let MavMessage::COMMAND_LONG(c) = &mut land else {
        unreachable!()
    };
    c.target_system = 2;
    let (events, _) = feed(&mut link, &ground.frame(&land), at(0.0));
    assert!(events.is_empty());
    let MavMessage::COMMAND_LONG(c) = &mut land else {
        unreachable!()
    };
    (c.target_system, c.target_component) = (1, 42);
    let (events, _) = feed(&mut link, &ground.frame(&land), at(0.0));
    assert!(events.is_empty());
    assert_eq!(link.counters().other_target, 2);
    // Broadcast (0) reaches every vehicle.
    let MavMessage::COMMAND_LONG(c) = &mut land else {
        unreachable!()
    };
    (c.target_system, c.target_component) = (0, 0);
    let (events, _) = feed(&mut link, &ground.frame(&land), at(0.0));
    assert_eq!(commands(&events), [GroundCommand::Land]);
}

#[test]
fn ground_heartbeats_are_reported_and_other_heartbeats_are_not() {
    let mut link = Link::new(LinkConfig::default());
    let mut ground = Ground::unsigned();
    let (events, _) = feed(&mut link, &ground.frame(&gcs_heartbeat()), at(0.0));
    assert_eq!(events, [InboundEvent::GroundHeartbeat { system_id: 255 }]);
    let MavMessage::HEARTBEAT(mut hb) = gcs_heartbeat() else {
        unreachable!()
    };
    hb.mavtype = plumbline_link::common::MavType::MAV_TYPE_ONBOARD_CONTROLLER;
    let (events, _) = feed(
        &mut link,
        &ground.frame(&MavMessage::HEARTBEAT(hb)),
        at(0.0),
    );
    assert!(events.is_empty());
    assert_eq!(link.counters().not_handled, 1);
}

#[test]
fn mavlink_1_frames_are_read_and_count_as_unsigned() {
    let land = command(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0, 0.0);
    let mut open = Link::new(LinkConfig::default());
    let (events, _) = feed(&mut open, &Ground::unsigned().frame_v1(&land), at(0.0));
    assert_eq!(commands(&events), [GroundCommand::Land]);
    let mut link = keyed();
    let (events, _) = feed(&mut link, &Ground::unsigned().frame_v1(&land), at(0.0));
    assert!(events.is_empty());
    assert_eq!(link.counters().unsigned, 1);
}

#[test]
fn with_a_key_only_signed_state_changes_are_obeyed() {
    let mut link = keyed();
    let kill = command(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 1.0, 0.0, 0.0);
    // Unsigned: refused and counted.
    let (events, _) = feed(&mut link, &Ground::unsigned().frame(&kill), at(0.0));
    assert!(events.is_empty());
    assert_eq!(link.counters().unsigned, 1);
    // Signed with another key: refused as a bad signature.
    let (events, _) = feed(&mut link, &Ground::signed([9; 32]).frame(&kill), at(0.0));
    assert!(events.is_empty());
    assert_eq!(link.counters().bad_signature, 1);
    // Signed with the key: obeyed.
    let mut ground = Ground::signed(KEY);
    let frame = ground.frame(&kill);
    let (events, _) = feed(&mut link, &frame, at(1.0));
    assert_eq!(commands(&events), [GroundCommand::Terminate]);
    // The same frame again is a replay.
    let (events, _) = feed(&mut link, &frame, at(1.0));
    assert!(events.is_empty());
    assert_eq!(link.counters().replayed, 1);
    // A fresh frame of the same stream is fine.
    let (events, _) = feed(&mut link, &ground.frame(&kill), at(2.0));
    assert_eq!(commands(&events), [GroundCommand::Terminate]);
    // An unsigned ground heartbeat does not keep the link alive (it would hold off the
    // link-lost failsafe for a station that is gone); a signed one does.
    let (events, _) = feed(
        &mut link,
        &Ground::unsigned().frame(&gcs_heartbeat()),
        at(2.0),
    );
    assert!(events.is_empty());
    assert_eq!(link.counters().unsigned, 2);
    let (events, _) = feed(&mut link, &ground.frame(&gcs_heartbeat()), at(3.0));
    assert_eq!(events, [InboundEvent::GroundHeartbeat { system_id: 255 }]);
}

#[test]
fn a_new_stream_more_than_a_minute_old_is_a_replay() {
    let mut link = keyed();
    let kill = command(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 1.0, 0.0, 0.0);
    let old = Ground::signed(KEY).frame(&kill);
    // The vehicle's clock is two minutes ahead of the recording's.
    let later = plumbline_link::LinkTime::since(unix_now() + 120.0, 0.0);
    let (events, _) = feed(&mut link, &old, later);
    assert!(events.is_empty());
    assert_eq!(link.counters().replayed, 1);
}

#[test]
fn the_outbound_stream_is_signed_with_the_key() {
    use mavlink::{SigningConfig, SigningData};
    let mut link = keyed();
    let mut out = Vec::new();
    link.announce(at(0.0), &mut out);
    link.announce(at(0.1), &mut out);
    let ground = SigningData::from_config(SigningConfig::new(KEY, 0, false, false));
    // Unsigned frames would fail here: the reader refuses them with allow_unsigned false.
    let decoded = decode_all(&out, Some(&ground));
    assert_eq!(decoded.len(), 2);
    let MavMessage::STATUSTEXT(t) = &decoded[0].1 else {
        panic!()
    };
    assert_eq!(
        t.text.to_str().unwrap(),
        "link signed: commands need the key"
    );
    let wrong = SigningData::from_config(SigningConfig::new([9; 32], 0, false, false));
    let mut reader = mavlink::MavlinkReader::new(&out[..]);
    assert!(reader
        .read_message_signed::<MavMessage>(mavlink::MavlinkVersion::V2, Some(&wrong))
        .is_err());
}

#[test]
fn without_a_key_the_link_says_so() {
    let mut link = Link::new(LinkConfig::default());
    assert!(!link.is_signed());
    let mut out = Vec::new();
    link.announce(at(0.0), &mut out);
    let decoded = decode_all(&out, None);
    let MavMessage::STATUSTEXT(t) = &decoded[0].1 else {
        panic!()
    };
    assert!(t.text.to_str().unwrap().starts_with("link unsigned"));
}

#[test]
fn a_companion_link_reads_its_own_autopilots_estimate_and_nobody_elses() {
    use plumbline_link::common::{ATTITUDE_DATA, LOCAL_POSITION_NED_DATA};
    use plumbline_link::{EstimatePart, COMPONENT_ONBOARD_COMPUTER};
    let companion = || {
        Link::new(LinkConfig {
            component_id: COMPONENT_ONBOARD_COMPUTER,
            ..LinkConfig::default()
        })
    };
    let position = MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
        time_boot_ms: 2000,
        x: 1.0,
        y: 2.0,
        z: -3.0,
        ..Default::default()
    });
    let attitude = MavMessage::ATTITUDE(ATTITUDE_DATA {
        time_boot_ms: 2010,
        yaw: 0.5,
        ..Default::default()
    });
    let mut autopilot = Ground::unsigned();
    autopilot.header.system_id = 1;
    autopilot.header.component_id = 1;
    let mut bytes = autopilot.frame(&position);
    bytes.extend(autopilot.frame(&attitude));
    let mut link = companion();
    let (events, replies) = feed(&mut link, &bytes, at(0.0));
    assert!(replies.is_empty());
    let parts: Vec<EstimatePart> = events
        .iter()
        .map(|e| match e {
            InboundEvent::Estimate(s) => s.part,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        parts,
        [
            EstimatePart::Position {
                position_m: [1.0, -2.0, 3.0]
            },
            EstimatePart::Heading { yaw_rad: -0.5 }
        ]
    );
    // Another vehicle's autopilot, a ground station's, or a vehicle's own link: not for this.
    for (system_id, component_id) in [(2, 1), (1, 190)] {
        let mut other = Ground::unsigned();
        other.header.system_id = system_id;
        other.header.component_id = component_id;
        let mut link = companion();
        let (events, _) = feed(&mut link, &other.frame(&position), at(0.0));
        assert!(events.is_empty() && link.counters().not_handled == 1);
    }
    let mut vehicle = Link::new(LinkConfig::default());
    let (events, _) = feed(&mut vehicle, &bytes, at(0.0));
    assert!(events.is_empty() && vehicle.counters().not_handled == 2);
}
