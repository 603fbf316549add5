//! The byte-stream side of the inbound path: any split, garbage, broken and unknown frames.
mod common;

use common::*;
use plumbline_link::common::{MavCmd, MavMessage, COMMAND_LONG_DATA, MANUAL_CONTROL_DATA};
use plumbline_link::{DropCounters, InboundEvent, Link, LinkConfig};
use proptest::prelude::*;

fn stream() -> Vec<u8> {
    let mut ground = Ground::unsigned();
    let mut bytes = ground.frame(&gcs_heartbeat());
    for (k, cmd) in [MavCmd::MAV_CMD_NAV_TAKEOFF, MavCmd::MAV_CMD_NAV_LAND]
        .into_iter()
        .enumerate()
    {
        bytes.extend(ground.frame(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            command: cmd,
            param7: k as f32,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        })));
    }
    bytes.extend(
        ground.frame(&MavMessage::MANUAL_CONTROL(MANUAL_CONTROL_DATA {
            x: 100,
            z: 500,
            target: 1,
            ..Default::default()
        })),
    );
    bytes
}

fn run(chunks: &[&[u8]]) -> (Vec<InboundEvent>, DropCounters) {
    let mut link = Link::new(LinkConfig::default());
    let mut events = Vec::new();
    let mut replies = Vec::new();
    for chunk in chunks {
        link.receive(chunk, at(0.0), &mut events, &mut replies);
    }
    (events, *link.counters())
}

#[test]
fn a_whole_stream_gives_one_event_per_message() {
    let (events, counters) = run(&[&stream()]);
    assert_eq!(events.len(), 4, "{events:?}");
    assert_eq!(counters, DropCounters::default());
}

#[test]
fn a_broken_checksum_is_counted_and_the_next_frame_still_arrives() {
    let mut bytes = stream();
    let first_len = Ground::unsigned().frame(&gcs_heartbeat()).len();
    bytes[first_len - 3] ^= 0x55; // inside the heartbeat's payload
    let (events, counters) = run(&[&bytes]);
    assert_eq!(events.len(), 3);
    assert_eq!(counters.bad_crc, 1);
}

#[test]
fn an_unknown_message_id_is_counted() {
    // A well-formed MAVLink 2 frame for id 60000, which the common dialect does not define.
    let mut frame = vec![0xFD, 2, 0, 0, 0, 255, 190, 0x60, 0xEA, 0x00, 1, 2];
    let crc = mavlink::calculate_crc(&frame[1..], 0);
    frame.extend(crc.to_le_bytes());
    let (events, counters) = run(&[&frame, &stream()]);
    assert_eq!(events.len(), 4);
    assert_eq!(counters.unknown_id, 1);
}

#[test]
fn unsupported_incompatibility_flags_are_counted() {
    let mut bytes = stream();
    bytes[2] = 0x04;
    let (events, counters) = run(&[&bytes]);
    assert_eq!(events.len(), 3);
    assert_eq!(counters.bad_header, 1);
}

proptest! {
    #[test]
    fn any_split_gives_the_same_events(cuts in prop::collection::vec(0usize..400, 0..12)) {
        let bytes = stream();
        let whole = run(&[&bytes]);
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c % (bytes.len() + 1)).collect();
        cuts.sort_unstable();
        let mut chunks = Vec::new();
        let mut from = 0;
        for c in cuts.into_iter().chain([bytes.len()]) {
            chunks.push(&bytes[from..c]);
            from = c;
        }
        prop_assert_eq!(run(&chunks), whole);
    }

    #[test]
    fn garbage_never_panics_and_frames_after_it_still_arrive(
        garbage in prop::collection::vec(any::<u8>(), 0..600),
    ) {
        let (_, counters) = run(&[&garbage]);
        prop_assert!(counters.skipped_bytes <= garbage.len() as u64);
        // Garbage, then the stream, then enough quiet to finish any false frame started in
        // the garbage: every real message still arrives.
        let mut bytes = garbage;
        bytes.extend(stream());
        bytes.extend([0u8; 300]);
        let (events, _) = run(&[&bytes]);
        prop_assert!(events.len() >= 4, "{:?}", events);
    }
}
