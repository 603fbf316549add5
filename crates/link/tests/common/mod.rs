//! A ground station built from the `mavlink` crate's own writer and reader, so the link is
//! checked against an implementation that is not its own.
#![allow(dead_code)] // each test file uses a different part

use mavlink::{MavHeader, MavlinkVersion, SigningConfig, SigningData};
use plumbline_link::common::{
    MavAutopilot, MavMessage, MavModeFlag, MavState, MavType, HEARTBEAT_DATA,
};
use plumbline_link::{InboundEvent, Link, LinkTime};
use std::time::{SystemTime, UNIX_EPOCH};

pub const KEY: [u8; 32] = [7; 32];
pub const GROUND_SYSTEM: u32 = 255;
pub const GROUND_COMPONENT: u8 = 190;

pub fn unix_now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

/// The time of a call `t_s` into a run that started now (signing uses the real clock because
/// the `mavlink` crate's signer does).
pub fn at(t_s: f64) -> LinkTime {
    LinkTime::since(unix_now() - t_s, t_s)
}

pub struct Ground {
    pub header: MavHeader,
    pub signing: Option<SigningData>,
}

impl Ground {
    pub fn unsigned() -> Self {
        Self {
            header: MavHeader {
                system_id: GROUND_SYSTEM,
                component_id: GROUND_COMPONENT,
                sequence: 0,
            },
            signing: None,
        }
    }

    pub fn signed(key: [u8; 32]) -> Self {
        Self {
            signing: Some(SigningData::from_config(SigningConfig::new(
                key, 0, true, false,
            ))),
            ..Self::unsigned()
        }
    }

    pub fn frame(&mut self, message: &MavMessage) -> Vec<u8> {
        let mut out = Vec::new();
        mavlink::write_v2_msg_signed(&mut out, self.header, message, self.signing.as_ref())
            .unwrap();
        self.header.sequence = self.header.sequence.wrapping_add(1);
        out
    }

    pub fn frame_v1(&mut self, message: &MavMessage) -> Vec<u8> {
        let mut out = Vec::new();
        mavlink::write_versioned_msg(&mut out, MavlinkVersion::V1, self.header, message).unwrap();
        out
    }
}

pub fn gcs_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// Feeds `bytes` to `link`; returns the events and the link's immediate replies.
pub fn feed(link: &mut Link, bytes: &[u8], now: LinkTime) -> (Vec<InboundEvent>, Vec<u8>) {
    let (mut events, mut replies) = (Vec::new(), Vec::new());
    link.receive(bytes, now, &mut events, &mut replies);
    (events, replies)
}

/// Every message in `bytes`, decoded by the `mavlink` crate (checking signatures with
/// `signing` when given).
pub fn decode_all(bytes: &[u8], signing: Option<&SigningData>) -> Vec<(MavHeader, MavMessage)> {
    let mut reader = mavlink::MavlinkReader::new(bytes);
    let mut out = Vec::new();
    loop {
        match reader.read_message_signed::<MavMessage>(MavlinkVersion::V2, signing) {
            Ok(m) => out.push(m),
            Err(mavlink::error::MessageReadError::Io(_)) => break,
            Err(e) => panic!("undecodable output: {e:?}"),
        }
    }
    out
}
