//! Frames in: finds MAVLink 1 and 2 frames in a byte stream that arrives in arbitrary pieces,
//! checks their CRC and hands each good one on. Garbage is skipped; a candidate that fails is
//! retried from its second byte, so a real frame hidden behind a false start marker is not lost.

use crate::counters::DropCounters;
use crate::crc::checksum;
use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};

const STX_V1: u8 = 0xFE;
const STX_V2: u8 = 0xFD;
const IFLAG_SIGNED: u8 = 0x01;
/// MAVLink 1 header after the marker: len, seq, sys, comp, msgid.
const V1_HEADER: usize = 5;
/// MAVLink 2 header after the marker: len, incompat, compat, seq, sys, comp, msgid (3).
const V2_HEADER: usize = 9;
const SIGNATURE_LEN: usize = 13;

/// One frame whose CRC checked out.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame<'a> {
    pub version: MavlinkVersion,
    /// The whole frame, marker to signature.
    pub bytes: &'a [u8],
    pub system_id: u8,
    pub component_id: u8,
    pub message_id: u32,
    pub payload: &'a [u8],
    pub signed: bool,
}

/// Carries an incomplete frame from one call to the next.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scanner {
    pending: Vec<u8>,
    /// Bytes of `pending` already consumed.
    start: usize,
}

enum Candidate {
    /// Not enough bytes yet to judge.
    Incomplete,
    /// Not a frame here: skip one byte and look again.
    Reject,
    /// A good frame of this many bytes.
    Frame(usize),
}

impl Scanner {
    /// Appends received bytes; what is left of earlier calls (at most one partial frame) stays
    /// in front of them.
    pub(crate) fn extend(&mut self, bytes: &[u8]) {
        self.pending.drain(..self.start);
        self.start = 0;
        self.pending.extend_from_slice(bytes);
    }

    /// The next good frame, or `None` when the bytes so far hold no more.
    pub(crate) fn next_frame(&mut self, counters: &mut DropCounters) -> Option<Frame<'_>> {
        while self.start < self.pending.len() {
            let rest = &self.pending[self.start..];
            let Some(offset) = rest.iter().position(|&b| b == STX_V1 || b == STX_V2) else {
                counters.skipped_bytes += rest.len() as u64;
                self.start = self.pending.len();
                break;
            };
            counters.skipped_bytes += offset as u64;
            self.start += offset;
            match judge(&self.pending[self.start..], counters) {
                Candidate::Incomplete => return None,
                Candidate::Reject => {
                    counters.skipped_bytes += 1;
                    self.start += 1;
                }
                Candidate::Frame(len) => {
                    let at = self.start;
                    self.start += len;
                    return Some(frame_at(&self.pending[at..at + len]));
                }
            }
        }
        None
    }
}

/// Decides what the bytes starting at a marker are; counts a rejection's reason.
fn judge(bytes: &[u8], counters: &mut DropCounters) -> Candidate {
    let v2 = bytes[0] == STX_V2;
    let header = if v2 { V2_HEADER } else { V1_HEADER };
    if bytes.len() < 1 + header {
        return Candidate::Incomplete;
    }
    let payload_len = usize::from(bytes[1]);
    let signed = v2 && bytes[2] & IFLAG_SIGNED != 0;
    if v2 && bytes[2] & !IFLAG_SIGNED != 0 {
        // An incompatibility flag this end does not implement: the frame cannot be read.
        counters.bad_header += 1;
        return Candidate::Reject;
    }
    let crc_end = 1 + header + payload_len;
    let len = crc_end + 2 + if signed { SIGNATURE_LEN } else { 0 };
    if bytes.len() < len {
        return Candidate::Incomplete;
    }
    let message_id = message_id(bytes, v2);
    // The dialect answers 0 for the CRC_EXTRA of an id it does not define; a few real
    // messages have 0 too, so only then ask whether the id exists. An unknown id cannot be
    // checked at all and is never passed on, whatever its checksum.
    let extra_crc = MavMessage::extra_crc(message_id);
    if extra_crc == 0 && MavMessage::default_message_from_id(message_id).is_none() {
        counters.unknown_id += 1;
        return Candidate::Reject;
    }
    let expected = u16::from_le_bytes([bytes[crc_end], bytes[crc_end + 1]]);
    if checksum(&[&bytes[1..crc_end]], extra_crc) == expected {
        Candidate::Frame(len)
    } else {
        counters.bad_crc += 1;
        Candidate::Reject
    }
}

/// The length and message id of the MAVLink 2 frame at the start of `bytes`, as this link
/// writes them, or `None` when no whole frame starts there: a caller packing the link's
/// output into datagrams keeps every frame whole. Reads the layout only, not the checksum.
pub fn frame_span(bytes: &[u8]) -> Option<(usize, u32)> {
    if bytes.len() < 1 + V2_HEADER || bytes[0] != STX_V2 {
        return None;
    }
    let signature = if bytes[2] & IFLAG_SIGNED != 0 {
        SIGNATURE_LEN
    } else {
        0
    };
    let len = 1 + V2_HEADER + usize::from(bytes[1]) + 2 + signature;
    (len <= bytes.len()).then(|| (len, message_id(bytes, true)))
}

fn message_id(bytes: &[u8], v2: bool) -> u32 {
    if v2 {
        u32::from_le_bytes([bytes[7], bytes[8], bytes[9], 0])
    } else {
        u32::from(bytes[5])
    }
}

fn frame_at(bytes: &[u8]) -> Frame<'_> {
    let v2 = bytes[0] == STX_V2;
    let (header, system_at) = if v2 { (V2_HEADER, 5) } else { (V1_HEADER, 3) };
    let payload_len = usize::from(bytes[1]);
    Frame {
        version: if v2 {
            MavlinkVersion::V2
        } else {
            MavlinkVersion::V1
        },
        bytes,
        system_id: bytes[system_at],
        component_id: bytes[system_at + 1],
        message_id: message_id(bytes, v2),
        payload: &bytes[1 + header..1 + header + payload_len],
        signed: v2 && bytes[2] & IFLAG_SIGNED != 0,
    }
}
