//! Neato XV-11 LDS before firmware 2.4: one 1446-byte frame per revolution,
//! `5A A5 00 C0 s0 s1` then 360 four-byte readings (the same reading layout as the newer
//! firmware). The two speed bytes are in undocumented clock ticks, so revolutions from this
//! decoder carry no RPM and no per-beam time.
//!
//! The frame has no checksum. A frame that lost bytes would silently swallow the start of the
//! next one and shift every beam after the gap, so a frame is handed out only once the next
//! frame's header follows it immediately (or the stream ends); otherwise it is dropped and
//! counted as `malformed`. The cost is one revolution of latency and a second buffer.

use super::xv11_revolution::{Revolution, BEAMS};
use super::DecodeStats;

pub const HEADER: [u8; 4] = [0x5A, 0xA5, 0x00, 0xC0];
const SPEED_LEN: usize = 2;
pub const FRAME_LEN: usize = HEADER.len() + SPEED_LEN + 4 * BEAMS;
const BODY_LEN: usize = FRAME_LEN - HEADER.len();

/// Bytes in, confirmed revolutions out. State: the frame being read and the frame waiting for
/// confirmation, about 3 KB.
#[derive(Clone, Debug)]
pub struct Xv11OldDecoder {
    building: [[u8; 4]; BEAMS],
    /// Header bytes matched so far while searching; `HEADER.len()` once inside a body.
    matched: usize,
    /// Bytes of the body read so far.
    body_pos: usize,
    frame_offset: u64,
    pending: Option<Revolution>,
    stats: DecodeStats,
}

impl Default for Xv11OldDecoder {
    fn default() -> Self {
        Self {
            building: [[0; 4]; BEAMS],
            matched: 0,
            body_pos: 0,
            frame_offset: 0,
            pending: None,
            stats: DecodeStats::default(),
        }
    }
}

impl Xv11OldDecoder {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn push(&mut self, byte: u8) -> Option<Revolution> {
        self.stats.bytes += 1;
        if self.matched == HEADER.len() {
            self.push_body(byte);
            return None;
        }
        if byte == HEADER[self.matched] {
            self.matched += 1;
            if self.matched == HEADER.len() {
                self.frame_offset = self.stats.bytes - HEADER.len() as u64;
                self.body_pos = 0;
                return self.pending.take().map(|rev| self.hand_out(rev));
            }
            return None;
        }
        if self.pending.take().is_some() {
            self.stats.malformed += 1;
        }
        // The header's bytes are all different, so a mismatch can only restart at its first byte.
        let restart = usize::from(byte == HEADER[0]);
        self.stats.skipped_bytes += (self.matched + 1 - restart) as u64;
        self.matched = restart;
        None
    }

    fn push_body(&mut self, byte: u8) {
        if let Some(r) = self.body_pos.checked_sub(SPEED_LEN) {
            self.building[r / 4][r % 4] = byte;
        }
        self.body_pos += 1;
        if self.body_pos == BODY_LEN {
            self.pending = Some(Revolution::from_readings(self.building, self.frame_offset));
            self.matched = 0;
        }
    }

    fn hand_out(&mut self, rev: Revolution) -> Revolution {
        self.stats.packets_ok += 1;
        self.stats.revolutions += 1;
        rev
    }

    /// Ends the stream: the last complete frame, unconfirmed because nothing follows it. A
    /// frame cut short by the end is dropped (its bytes stay counted in `bytes` only).
    pub fn finish(&mut self) -> Option<Revolution> {
        self.pending.take().map(|rev| self.hand_out(rev))
    }

    pub fn stats(&self) -> DecodeStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::test_encoders::{decode_all, xv11_reading};
    extern crate std;
    use std::vec::Vec;

    fn frame(distance: impl Fn(usize) -> u16) -> Vec<u8> {
        let mut f = std::vec![0x5A, 0xA5, 0x00, 0xC0, 0x94, 0xD1];
        for deg in 0..BEAMS {
            f.extend_from_slice(&xv11_reading(distance(deg), false, 50));
        }
        f
    }

    fn decode(bytes: &[u8]) -> (Vec<Revolution>, DecodeStats) {
        decode_all::<Xv11OldDecoder>(bytes)
    }

    #[test]
    fn frames_are_confirmed_by_the_next_header_and_the_last_by_the_end() {
        let stream = [frame(|d| 100 + d as u16), frame(|_| 700)].concat();
        let mut d = Xv11OldDecoder::new();
        let early: Vec<Revolution> = stream.iter().filter_map(|&b| d.push(b)).collect();
        assert_eq!(early.len(), 1);
        assert_eq!(early[0].reading(359).map(|r| r.distance_mm), Some(459));
        assert_eq!(early[0].rpm(), None);
        assert_eq!(
            d.finish().and_then(|r| r.reading(0)).map(|r| r.distance_mm),
            Some(700)
        );
        assert_eq!(d.stats().revolutions, 2);
    }

    #[test]
    fn torn_frame_is_dropped_not_shifted() {
        let mut stream = [frame(|_| 1), frame(|_| 2), frame(|_| 3), frame(|_| 4)].concat();
        stream.drain(FRAME_LEN + 100..FRAME_LEN + 108); // frame 2 loses two readings
        let (revs, stats) = decode(&stream);
        // Frame 2 swallowed frame 3's header: both are lost, frames 1 and 4 survive intact.
        let firsts: Vec<u16> = revs
            .iter()
            .filter_map(|r| r.reading(0))
            .map(|r| r.distance_mm)
            .collect();
        assert_eq!(firsts, [1, 4]);
        assert_eq!(stats.malformed, 1);
    }

    #[test]
    fn garbage_before_a_header_is_skipped() {
        let stream = [&[0x5A, 0x5A, 0xA5, 0x01, 0x5A][..], &frame(|_| 9)].concat();
        let (revs, stats) = decode(&stream);
        assert_eq!(revs.len(), 1);
        assert_eq!(stats.skipped_bytes, 5);
    }
}
