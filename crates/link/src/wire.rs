//! Frames out: one MAVLink 2 frame per message appended to the caller's buffer, with this end's
//! system and component ids, a running sequence number and, with a key, a signature.

use crate::signing::Signer;
use mavlink::dialects::common::MavMessage;
use mavlink::{MAVLinkV2MessageRaw, MavHeader};

/// Writes frames; owns the sequence number and the signing state of the outbound stream.
#[derive(Clone, Debug)]
pub(crate) struct FrameWriter {
    header: MavHeader,
    /// Reused for every frame so writing allocates nothing beyond the caller's buffer growth.
    raw: MAVLinkV2MessageRaw,
}

impl FrameWriter {
    pub(crate) fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            header: MavHeader {
                system_id: u32::from(system_id),
                component_id,
                sequence: 0,
            },
            raw: MAVLinkV2MessageRaw::new(),
        }
    }

    pub(crate) fn system_id(&self) -> u8 {
        self.header.system_id as u8
    }

    pub(crate) fn component_id(&self) -> u8 {
        self.header.component_id
    }

    /// Appends `message` as one frame to `out`; signed when `signer` is given.
    pub(crate) fn write(
        &mut self,
        message: &MavMessage,
        signer: Option<&mut Signer>,
        unix_s: f64,
        out: &mut Vec<u8>,
    ) {
        match signer {
            Some(signer) => {
                self.raw.serialize_message_for_signing(self.header, message);
                signer.sign(&mut self.raw, unix_s);
            }
            None => {
                // The buffer is reused: clear the signed flag a previous frame may have left.
                *self.raw.incompatibility_flags_mut() = 0;
                self.raw.serialize_message(self.header, message);
            }
        }
        out.extend_from_slice(self.raw.raw_bytes());
        self.header.sequence = self.header.sequence.wrapping_add(1);
    }
}
