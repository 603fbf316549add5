//! Neato XV-11 LDS, firmware 2.4 and later: the 22-byte `0xFA` packet.
//!
//! Layout (see `data/captures/neato-xv11/SOURCE.md`): `FA idx spdL spdH`, four 4-byte
//! readings, `chkL chkH`. `idx` is `0xA0 + k` for packet k of 90 in a revolution; packet k holds
//! the readings at k*4 .. k*4+3 degrees, clockwise. Speed is u16 LE in 1/64 RPM.

use super::DecodeStats;

pub const PACKET_LEN: usize = 22;
pub const PACKETS_PER_REV: usize = 90;
pub const READINGS_PER_PACKET: usize = 4;
const START: u8 = 0xFA;
const FIRST_INDEX: u8 = 0xA0;

/// One distance reading as the device sends it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reading {
    /// 14-bit distance; meaningless (an error code) when `invalid` is set.
    pub distance_mm: u16,
    /// Bit 15: the device found no usable return.
    pub invalid: bool,
    /// Bit 14: the return was weak for its distance; the distance is still reported.
    pub strength_warning: bool,
    pub strength: u16,
}

impl Reading {
    /// Decodes the 4 raw bytes `b0 b1 b2 b3` of one reading (same layout in both firmwares).
    pub fn from_bytes(b: [u8; 4]) -> Self {
        Self {
            distance_mm: u16::from(b[0]) | (u16::from(b[1] & 0x3F) << 8),
            invalid: b[1] & 0x80 != 0,
            strength_warning: b[1] & 0x40 != 0,
            strength: u16::from_le_bytes([b[2], b[3]]),
        }
    }
}

/// A packet that passed its checksum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet {
    /// 0..90: which 4 degrees of the revolution this packet covers.
    pub index: u8,
    /// Motor speed in 1/64 RPM.
    pub speed_q6: u16,
    /// The raw readings, decoded on demand with [`Reading::from_bytes`] to keep packets small.
    pub readings: [[u8; 4]; READINGS_PER_PACKET],
    /// Stream offset of the packet's `0xFA` byte.
    pub offset: u64,
}

impl Packet {
    pub fn rpm(&self) -> f32 {
        f32::from(self.speed_q6) / 64.0
    }

    pub fn reading(&self, i: usize) -> Option<Reading> {
        self.readings.get(i).map(|&b| Reading::from_bytes(b))
    }
}

/// The device checksum over the first 20 bytes taken as ten u16 LE words.
pub fn checksum(bytes: &[u8]) -> u16 {
    let mut chk32: u32 = 0;
    for w in bytes.chunks_exact(2).take(10) {
        chk32 = (chk32 << 1).wrapping_add(u32::from(u16::from_le_bytes([w[0], w[1]])));
    }
    (((chk32 & 0x7FFF) + (chk32 >> 15)) & 0x7FFF) as u16
}

fn is_index(b: u8) -> bool {
    (FIRST_INDEX..FIRST_INDEX + PACKETS_PER_REV as u8).contains(&b)
}

/// Finds packets in a byte stream: resynchronises on `0xFA` followed by a valid index byte and,
/// after a bad checksum, searches the rejected bytes for the next start rather than skipping all
/// 22 (a real start can hide inside garbage). State: 22 bytes of buffer plus counters.
#[derive(Clone, Debug, Default)]
pub struct PacketParser {
    buf: [u8; PACKET_LEN],
    len: usize,
    pub stats: DecodeStats,
}

impl PacketParser {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one byte; returns a packet when this byte completed one with a good checksum.
    pub fn push(&mut self, byte: u8) -> Option<Packet> {
        self.push_slice(&[byte]).1
    }

    /// Feeds bytes until a packet completes: returns how many bytes were consumed and the
    /// packet, if any (call again with the rest). Copies packet bodies in bulk, which is what
    /// makes file decoding fast; the per-byte work is only the search for a start.
    pub fn push_slice(&mut self, bytes: &[u8]) -> (usize, Option<Packet>) {
        let mut i = 0;
        let mut packet = None;
        while i < bytes.len() && packet.is_none() {
            let rest = &bytes[i..];
            if self.len == 0 {
                let skip = rest.iter().position(|&b| b == START).unwrap_or(rest.len());
                self.stats.skipped_bytes += skip as u64;
                i += skip;
                if skip < rest.len() {
                    self.buf[0] = START;
                    self.len = 1;
                    i += 1;
                }
                continue;
            }
            let take = (PACKET_LEN - self.len).min(rest.len());
            if take == 1 {
                // The one-byte `push` path: a plain store, not a memcpy call.
                self.buf[self.len] = rest[0];
            } else {
                self.buf[self.len..self.len + take].copy_from_slice(&rest[..take]);
            }
            let was = self.len;
            self.len += take;
            i += take;
            if was == 1 && !is_index(self.buf[1]) {
                // Only the index byte is kept for a new search; the rest is read again.
                i -= take - 1;
                self.len = 2;
                self.resync(1);
            } else if self.len == PACKET_LEN {
                packet = self.complete(self.stats.bytes + i as u64);
            }
        }
        self.stats.bytes += i as u64;
        (i, packet)
    }

    /// Checks a full buffer that ended at stream offset `end`; on a bad checksum searches it
    /// for the next start.
    fn complete(&mut self, end: u64) -> Option<Packet> {
        let got = u16::from_le_bytes([self.buf[20], self.buf[21]]);
        if checksum(&self.buf[..20]) != got {
            self.stats.bad_checksum += 1;
            self.resync(1);
            return None;
        }
        self.len = 0;
        self.stats.packets_ok += 1;
        let b = &self.buf;
        let mut readings = [[0u8; 4]; READINGS_PER_PACKET];
        for (i, r) in readings.iter_mut().enumerate() {
            r.copy_from_slice(&b[4 + 4 * i..8 + 4 * i]);
        }
        Some(Packet {
            index: b[1] - FIRST_INDEX,
            speed_q6: u16::from_le_bytes([b[2], b[3]]),
            readings,
            offset: end - PACKET_LEN as u64,
        })
    }

    /// Drops the buffered bytes before the next plausible start at or after `from`, keeping the
    /// rest buffered; dropped bytes are counted as skipped.
    fn resync(&mut self, from: usize) {
        let mut start = from;
        while start < self.len {
            let next_ok = start + 1 >= self.len || is_index(self.buf[start + 1]);
            if self.buf[start] == START && next_ok {
                break;
            }
            start += 1;
        }
        self.stats.skipped_bytes += start as u64;
        self.buf.copy_within(start..self.len, 0);
        self.len -= start;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::test_encoders::xv11_packet as packet_bytes;
    extern crate std;
    use std::{vec, vec::Vec};

    fn feed(p: &mut PacketParser, bytes: &[u8]) -> usize {
        bytes.iter().filter_map(|&b| p.push(b)).count()
    }

    #[test]
    fn reading_bits_follow_the_documented_layout() {
        let r = Reading::from_bytes([0x34, 0x12 | 0x40, 0x78, 0x56]);
        assert_eq!(r.distance_mm, 0x1234);
        assert!(r.strength_warning && !r.invalid);
        assert_eq!(r.strength, 0x5678);
        assert!(Reading::from_bytes([0, 0x80, 0, 0]).invalid);
    }

    #[test]
    fn checksum_of_a_real_packet_matches() {
        // The first complete packet of hand_in_box.bin, at byte 6.
        let p: [u8; 22] = [
            0xFA, 0xDA, 0x43, 0x4A, 0x3D, 0x02, 0x29, 0x01, 0x34, 0x02, 0x20, 0x01, 0x2D, 0x02,
            0x2C, 0x01, 0x24, 0x02, 0x36, 0x01, 0xDA, 0x17,
        ];
        assert_eq!(checksum(&p[..20]), 0x17DA);
        let mut parser = PacketParser::new();
        let got: Vec<Packet> = p.iter().filter_map(|&b| parser.push(b)).collect();
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].index, 58);
        assert_eq!(got[0].rpm(), f32::from(0x4A43u16) / 64.0);
        assert_eq!(got[0].reading(0).map(|r| r.distance_mm), Some(573));
    }

    #[test]
    fn garbage_then_packet_resynchronises_and_counts() {
        let pkt = packet_bytes(5, 300 * 64, [[1, 0, 0, 0]; 4]);
        let mut stream = vec![0x00, 0xFA, 0x11, 0xFA];
        stream.extend_from_slice(&pkt);
        let mut p = PacketParser::new();
        assert_eq!(feed(&mut p, &stream), 1);
        assert_eq!(p.stats.skipped_bytes, 4);
        assert_eq!(p.stats.packets_ok, 1);
    }

    #[test]
    fn a_start_hidden_in_a_bad_packet_is_found() {
        let good = packet_bytes(7, 64, [[9, 0, 0, 0]; 4]);
        // A torn packet: its first 10 bytes, then a whole good packet.
        let mut stream = good[..10].to_vec();
        stream[1] = 0xA3;
        stream.extend_from_slice(&good);
        let mut p = PacketParser::new();
        assert_eq!(feed(&mut p, &stream), 1);
        assert_eq!(p.stats.bad_checksum, 1);
        assert_eq!(p.stats.skipped_bytes, 10);
    }

    #[test]
    fn corrupted_byte_is_a_bad_checksum_not_a_packet() {
        let mut pkt = packet_bytes(3, 64, [[1, 2, 3, 4]; 4]);
        pkt[9] ^= 0x01;
        let mut p = PacketParser::new();
        assert_eq!(feed(&mut p, &pkt), 0);
        assert_eq!(p.stats.bad_checksum, 1);
    }
}
