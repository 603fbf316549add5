//! Byte encoders for tests, written from the protocol documents and independently of the
//! decoders: a decoder test that builds its input with the decoder's own code proves nothing.

extern crate std;
use std::vec::Vec;

/// An XV-11 (firmware >= 2.4) packet with a correct checksum, computed here from the documented
/// rule rather than with the decoder's `checksum`.
pub fn xv11_packet(index: u8, speed_q6: u16, readings: [[u8; 4]; 4]) -> [u8; 22] {
    let mut p = [0u8; 22];
    p[0] = 0xFA;
    p[1] = 0xA0 + index;
    p[2..4].copy_from_slice(&speed_q6.to_le_bytes());
    for (i, r) in readings.iter().enumerate() {
        p[4 + 4 * i..8 + 4 * i].copy_from_slice(r);
    }
    let mut c: u64 = 0;
    for i in 0..10 {
        c = c * 2 + u64::from(p[2 * i]) + 256 * u64::from(p[2 * i + 1]);
    }
    let c = ((c % 32768) + (c / 32768)) % 32768;
    p[20] = (c % 256) as u8;
    p[21] = (c / 256) as u8;
    p
}

/// One XV-11 reading: distance in mm with the invalid flag, strength.
pub fn xv11_reading(distance_mm: u16, invalid: bool, strength: u16) -> [u8; 4] {
    let hi = (distance_mm >> 8) as u8 & 0x3F;
    let flag = if invalid { 0x80 } else { 0 };
    [
        distance_mm as u8,
        hi | flag,
        strength as u8,
        (strength >> 8) as u8,
    ]
}

/// A whole revolution of XV-11 packets 0..90 where reading k has distance `range(k)` mm.
pub fn xv11_revolution(speed_q6: u16, range: impl Fn(usize) -> u16) -> Vec<u8> {
    let mut out = Vec::new();
    for k in 0..90u8 {
        let r = core::array::from_fn(|i| xv11_reading(range(usize::from(k) * 4 + i), false, 100));
        out.extend_from_slice(&xv11_packet(k, speed_q6, r));
    }
    out
}

/// A SCIP 2.0 value in `chars` characters: 6 bits each, most significant first, plus 0x30.
pub fn scip_encode(value: u32, chars: usize) -> Vec<u8> {
    (0..chars)
        .rev()
        .map(|i| ((value >> (6 * i)) & 0x3F) as u8 + 0x30)
        .collect()
}

/// A SCIP 2.0 line: payload, sum character (low 6 bits of the byte sum, plus 0x30), LF.
pub fn scip_line(payload: &[u8]) -> Vec<u8> {
    let sum: u32 = payload.iter().map(|&b| u32::from(b)).sum();
    let mut line = payload.to_vec();
    line.push((sum % 64) as u8 + 0x30);
    line.push(b'\n');
    line
}

/// A whole scan reply: echo, status, timestamp, values cut into 64-character data lines,
/// and the empty line that closes it.
pub fn scip_scan_reply(
    echo: &[u8],
    status: &[u8],
    timestamp_ms: u32,
    values: &[u32],
    chars: usize,
) -> Vec<u8> {
    let mut out = echo.to_vec();
    out.push(b'\n');
    out.extend(scip_line(status));
    out.extend(scip_line(&scip_encode(timestamp_ms, 4)));
    let data: Vec<u8> = values.iter().flat_map(|&v| scip_encode(v, chars)).collect();
    for chunk in data.chunks(64) {
        out.extend(scip_line(chunk));
    }
    out.push(b'\n');
    out
}

/// The RPLIDAR response descriptor for a standard scan: sync A5 5A, length 5 and "multiple
/// response" mode packed in 32 bits LE, data type 0x81.
pub fn rplidar_descriptor() -> Vec<u8> {
    let len_and_mode: u32 = 5 | (1 << 30);
    let mut out = std::vec![0xA5, 0x5A];
    out.extend_from_slice(&len_and_mode.to_le_bytes());
    out.push(0x81);
    out
}

/// One RPLIDAR standard-scan node from clockwise degrees and millimetres.
pub fn rplidar_node(start: bool, quality: u8, angle_deg: f64, distance_mm: f64) -> [u8; 5] {
    let flags = if start { 0b01 } else { 0b10 };
    let angle = ((angle_deg * 64.0).round() as u16) << 1 | 1;
    let dist = (distance_mm * 4.0).round() as u16;
    let [a0, a1] = angle.to_le_bytes();
    let [d0, d1] = dist.to_le_bytes();
    [quality << 2 | flags, a0, a1, d0, d1]
}

/// Every revolution a fresh decoder makes of `bytes`, and its counters.
pub fn decode_all<D: crate::lidar::ByteDecoder + Default>(
    bytes: &[u8],
) -> (Vec<D::Revolution>, crate::lidar::DecodeStats) {
    let mut d = D::default();
    let mut out = Vec::new();
    d.decode_into(bytes, &mut out);
    (out, d.stats())
}
