//! Bytes a real ground station (pymavlink) wrote, recorded in `data/mavlink/` by the script
//! beside them: the link must turn them into the commands pymavlink meant; and an autopilot's
//! estimate as a companion's link reads it back.
mod common;

use common::feed;
use plumbline_core::msgs::{GroundCommand, GroundMode};
use plumbline_link::{
    InboundEvent, Link, LinkConfig, LinkTime, ParamRef, ParamRequest, SigningKey,
};

fn fixture(name: &str) -> Vec<u8> {
    let path = format!("{}/../../data/mavlink/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The Unix time of the signed fixture's timestamp (600000000000 ticks of 10 us after 2015).
const SIGNED_AT_UNIX_S: f64 = 1_420_070_400.0 + 6_000_000.0;

fn keyed() -> Link {
    Link::new(LinkConfig {
        key: Some(SigningKey {
            secret: [7; 32],
            link_id: 3,
        }),
        ..LinkConfig::default()
    })
}

#[test]
fn a_pymavlink_session_gives_the_commands_it_sent() {
    let mut link = Link::new(LinkConfig::default());
    let (events, replies) = feed(
        &mut link,
        &fixture("ground-unsigned.bin"),
        LinkTime::since(0.0, 0.0),
    );
    assert!(replies.is_empty());
    assert_eq!(*link.counters(), Default::default());
    let summary: Vec<String> = events
        .iter()
        .map(|e| match e {
            InboundEvent::Command { command, .. } => format!("{command:?}"),
            InboundEvent::GroundHeartbeat { system_id } => format!("heartbeat {system_id}"),
            InboundEvent::Param { request, from } => {
                assert_eq!((from.system_id, from.component_id), (255, 190));
                match request {
                    ParamRequest::List => "list".into(),
                    ParamRequest::Read(ParamRef::Name(n)) => {
                        format!("read {}", n.as_str().unwrap())
                    }
                    ParamRequest::Read(ParamRef::Index(i)) => format!("read #{i}"),
                    ParamRequest::Set { name, value } => {
                        format!("set {} {value}", name.as_str().unwrap())
                    }
                }
            }
            InboundEvent::Estimate(s) => format!("estimate {s:?}"),
        })
        .collect();
    let sticks = match events[4] {
        InboundEvent::Command {
            command: GroundCommand::Sticks(s),
            ack: None,
        } => s,
        ref other => panic!("{other:?}"),
    };
    assert_eq!(
        (sticks.pitch_norm, sticks.roll_norm, sticks.throttle_norm),
        (0.2, -0.1, 0.6)
    );
    assert_eq!(
        summary,
        [
            "heartbeat 255".to_string(),
            format!("{:?}", GroundCommand::Arm),
            format!(
                "{:?}",
                GroundCommand::Takeoff {
                    height_m: Some(1.5)
                }
            ),
            format!("{:?}", GroundCommand::SetMode(GroundMode::Explore)),
            format!("{:?}", GroundCommand::Sticks(sticks)),
            "list".into(),
            "read POS_XY_P".into(),
            "set POS_XY_P 2.5".into(),
            format!("{:?}", GroundCommand::Land),
            format!("{:?}", GroundCommand::Terminate),
        ]
    );
}

#[test]
fn with_a_key_pymavlinks_unsigned_state_changes_are_refused() {
    let mut link = keyed();
    let (events, _) = feed(
        &mut link,
        &fixture("ground-unsigned.bin"),
        LinkTime::since(0.0, 0.0),
    );
    // The two parameter reads change nothing and still arrive; the unsigned heartbeat does
    // not keep the link alive, so it is refused with the state changes.
    assert_eq!(events.len(), 2, "{events:?}");
    assert!(events
        .iter()
        .all(|e| matches!(e, InboundEvent::Param { .. })));
    assert_eq!(link.counters().unsigned, 8);
}

#[test]
fn pymavlinks_signed_kill_is_obeyed_once() {
    let mut link = keyed();
    let now = LinkTime {
        t_s: 0.0,
        unix_s: SIGNED_AT_UNIX_S,
    };
    let signed = fixture("ground-signed.bin");
    let (events, _) = feed(&mut link, &signed, now);
    assert!(
        matches!(
            events[..],
            [InboundEvent::Command {
                command: GroundCommand::Terminate,
                ack: Some(_)
            }]
        ),
        "{events:?}"
    );
    let (events, _) = feed(&mut link, &signed, now);
    assert!(events.is_empty());
    assert_eq!(link.counters().replayed, 1);
    // Played back to a vehicle whose clock is an hour on, it is a replay too.
    let mut later = keyed();
    let (events, _) = feed(
        &mut later,
        &signed,
        LinkTime {
            t_s: 0.0,
            unix_s: SIGNED_AT_UNIX_S + 3600.0,
        },
    );
    assert!(events.is_empty());
    assert_eq!(later.counters().replayed, 1);
}

#[test]
fn a_pymavlink_autopilots_estimate_becomes_enu_samples_a_watch_judges() {
    use plumbline_link::{
        EstimatePart, EstimateWatch, OdometryPose, Withheld, COMPONENT_ONBOARD_COMPUTER,
    };
    let mut link = Link::new(LinkConfig {
        component_id: COMPONENT_ONBOARD_COMPUTER,
        ..LinkConfig::default()
    });
    let (events, replies) = feed(
        &mut link,
        &fixture("autopilot-estimate.bin"),
        LinkTime::since(0.0, 1.0),
    );
    assert!(replies.is_empty());
    // The autopilot's heartbeat is not an estimate.
    assert_eq!(link.counters().not_handled, 1);
    let samples: Vec<_> = events
        .iter()
        .map(|e| match e {
            InboundEvent::Estimate(s) => *s,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(samples.len(), 5);
    assert_eq!(samples[0].autopilot_s, 61.5);
    // 2 m north, 1 m east, 1.5 m up: x 2, y -1, z 1.5; yaw 0.5 rad clockwise is -0.5.
    assert_eq!(
        samples[0].part,
        EstimatePart::Position {
            position_m: [2.0, -1.0, 1.5]
        }
    );
    assert_eq!(samples[1].part, EstimatePart::Heading { yaw_rad: -0.5 });
    let EstimatePart::Pose(OdometryPose {
        position_m,
        yaw_rad,
        valid: true,
        reset_counter: 2,
    }) = samples[2].part
    else {
        panic!("{:?}", samples[2]);
    };
    assert_eq!(position_m, [2.0, -1.0, 1.5]);
    assert!((yaw_rad + 0.5).abs() < 1e-5, "{yaw_rad}");
    assert!(matches!(
        samples[3].part,
        EstimatePart::Pose(OdometryPose { valid: false, .. })
    ));
    // One after another into a watch: position and heading make an estimate, the good
    // ODOMETRY replaces them (a switch of source), the failed one is refused and, fresh, stays
    // preferred over the position that follows (whose north is NaN).
    let mut watch = EstimateWatch::new(0.5);
    let mut verdicts = Vec::new();
    for (i, s) in samples.iter().enumerate() {
        let arrival = 1.0 + 0.01 * i as f64;
        watch.take(s, arrival);
        verdicts.push(watch.reading(arrival).map(|e| e.position_m));
    }
    assert_eq!(
        verdicts,
        [
            Err(Withheld::Stale),
            Ok([2.0, -1.0, 1.5]),
            Err(Withheld::Discontinuity),
            Err(Withheld::Invalid),
            Err(Withheld::Invalid),
        ]
    );
}
