//! Frames out: one MAVLink 2 frame per message appended to the caller's buffer, with this end's
//! system and component ids, a running sequence number and, with a key, a signature.
//!
//! The payload is the `mavlink` crate's serialization; the frame around it (nine header bytes,
//! checksum, signature trailer) is written here, straight into the caller's buffer, so a frame
//! costs no copy through a 280-byte staging buffer and no generic checksum.

use crate::crc::checksum;
use crate::signing::Signer;
use mavlink::dialects::common::MavMessage;
use mavlink::{MAVLinkV2MessageRaw, MavlinkVersion, Message};

const STX_V2: u8 = 0xFD;
const IFLAG_SIGNED: u8 = 0x01;
/// Header after the marker: len, incompat, compat, seq, sys, comp, msgid (3 bytes).
const HEADER_LEN: usize = 10;
const SIGNATURE_LEN: usize = 13;

/// Writes frames; owns the sequence number of the outbound stream.
#[derive(Clone, Debug)]
pub(crate) struct FrameWriter {
    system_id: u8,
    component_id: u8,
    sequence: u8,
    payload: [u8; 255],
    /// Staging for the signature computation (the `mavlink` crate hashes a raw frame).
    signing_buf: MAVLinkV2MessageRaw,
}

impl FrameWriter {
    pub(crate) fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            system_id,
            component_id,
            sequence: 0,
            payload: [0; 255],
            signing_buf: MAVLinkV2MessageRaw::new(),
        }
    }

    pub(crate) fn system_id(&self) -> u8 {
        self.system_id
    }

    pub(crate) fn component_id(&self) -> u8 {
        self.component_id
    }

    /// Appends `message` as one frame to `out`; signed when `signer` is given.
    pub(crate) fn write(
        &mut self,
        message: &MavMessage,
        signer: Option<&mut Signer>,
        unix_s: f64,
        out: &mut Vec<u8>,
    ) {
        let len = message.ser(MavlinkVersion::V2, &mut self.payload);
        let id = message.message_id().to_le_bytes();
        let header: [u8; HEADER_LEN] = [
            STX_V2,
            len as u8,
            if signer.is_some() { IFLAG_SIGNED } else { 0 },
            0,
            self.sequence,
            self.system_id,
            self.component_id,
            id[0],
            id[1],
            id[2],
        ];
        let payload = &self.payload[..len];
        let crc = checksum(
            &[&header[1..], payload],
            MavMessage::extra_crc(message.message_id()),
        );
        let start = out.len();
        out.extend_from_slice(&header);
        out.extend_from_slice(payload);
        out.extend_from_slice(&crc.to_le_bytes());
        if let Some(signer) = signer {
            out.extend_from_slice(&[0; SIGNATURE_LEN]);
            let frame = &mut out[start..];
            self.signing_buf.as_mut_slice()[..frame.len()].copy_from_slice(frame);
            signer.sign(&mut self.signing_buf, unix_s);
            frame.copy_from_slice(&self.signing_buf.as_slice()[..frame.len()]);
        }
        self.sequence = self.sequence.wrapping_add(1);
    }
}
