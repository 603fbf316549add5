//! Slamtec RPLIDAR A1/A2 standard scan (`SCAN` request `A5 20`).
//!
//! The device answers with the response descriptor `A5 5A 05 00 00 40 81` (5-byte nodes, sent
//! repeatedly, type 0x81) and then 5-byte measurement nodes (Slamtec protocol document,
//! "SCAN" response):
//! - byte 0: quality (6 bits) << 2 | !S << 1 | S, where S marks the first node of a revolution;
//! - bytes 1-2: C (check bit, always 1) | angle_q6 << 1, u16 LE, degrees * 64, clockwise;
//! - bytes 3-4: distance_q2, u16 LE, millimetres * 4; 0 means no return.
//!
//! The two check bits are the only integrity check, so a node is also rejected when its angle
//! is beyond 360 degrees. After a rejected node the decoder slides one byte at a time until
//! nodes pass again. A descriptor (which no node can be mistaken for: its second byte has the
//! check bit clear) restarts the stream. Recording may start mid-scan, so it is optional.
//!
//! Two check bits pass a quarter of random windows, so a revolution is handed out only when it
//! is one an RPLIDAR can send: at least [`MIN_NODES_PER_REV`] nodes (at the A1/A2 sample rates,
//! slower than about 1200 rpm; a partial first or last revolution shorter than that is dropped
//! too), each node at most [`MAX_NODE_STEP_DEG`] clockwise of the one before, and all of them
//! sweeping at most one turn. Random bytes or another device's stream fail all three.

use super::DecodeStats;
use crate::geom::normalize_angle;
use crate::scan::{Beam, Scan};

pub const DESCRIPTOR: [u8; 7] = [0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
const NODE_LEN: usize = 5;
const FULL_TURN_Q6: u16 = 360 * 64;

/// Fewest nodes in a revolution: at 2000-4000 samples a second (A1, A2 standard scan) a turn of
/// fewer would be faster than the 15 Hz (900 rpm) the fastest model reaches, with margin.
pub const MIN_NODES_PER_REV: usize = 100;
/// Largest clockwise step between consecutive nodes: about 1 degree in normal running, 3.6 at
/// the fewest nodes a turn; more room for a node or two lost to bad check bits.
pub const MAX_NODE_STEP_DEG: u16 = 15;

/// One measurement as sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Node {
    pub quality: u8,
    /// Clockwise degrees * 64.
    pub angle_q6: u16,
    /// Millimetres * 4; 0 = no return.
    pub distance_q2: u16,
}

impl Node {
    /// Parses 5 bytes; `None` when the check bits or the angle are impossible. The bool is S.
    pub fn parse(b: [u8; NODE_LEN]) -> Option<(Node, bool)> {
        let start = b[0] & 1 != 0;
        let inverse = b[0] & 2 != 0;
        let check = b[1] & 1 != 0;
        let angle_q6 = u16::from_le_bytes([b[1], b[2]]) >> 1;
        if start == inverse || !check || angle_q6 >= FULL_TURN_Q6 {
            return None;
        }
        let node = Node {
            quality: b[0] >> 2,
            angle_q6,
            distance_q2: u16::from_le_bytes([b[3], b[4]]),
        };
        Some((node, start))
    }
}

/// Geometry and timing the byte stream does not carry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RplidarConfig {
    /// Time between nodes; the device's `GET_SAMPLERATE` answer (about 0.5 ms on an A1 in
    /// standard mode).
    pub sample_period_s: f32,
    /// Distances at or beyond this are not trusted (A1: 12 m).
    pub max_range_m: f32,
}

impl RplidarConfig {
    pub const A1: RplidarConfig = RplidarConfig {
        sample_period_s: 0.0005,
        max_range_m: 12.0,
    };
}

/// The nodes of one revolution in arrival order, at most `N`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RplidarRevolution<const N: usize> {
    nodes: [Node; N],
    len: usize,
    /// True when it began with an S node (the first one after start-up usually does not).
    pub starts_at_sync: bool,
}

impl<const N: usize> Default for RplidarRevolution<N> {
    fn default() -> Self {
        Self {
            nodes: [Node::default(); N],
            len: 0,
            starts_at_sync: false,
        }
    }
}

impl<const N: usize> RplidarRevolution<N> {
    pub fn nodes(&self) -> &[Node] {
        &self.nodes[..self.len]
    }

    /// Whether an RPLIDAR can have sent these nodes as one revolution (limits in the module docs).
    pub fn is_plausible(&self) -> bool {
        let nodes = self.nodes();
        if nodes.len() < MIN_NODES_PER_REV {
            return false;
        }
        let mut swept_q6: u32 = 0;
        for w in nodes.windows(2) {
            let step = (w[1].angle_q6 + FULL_TURN_Q6 - w[0].angle_q6) % FULL_TURN_Q6;
            if step > MAX_NODE_STEP_DEG * 64 {
                return false;
            }
            swept_q6 += u32::from(step);
        }
        swept_q6 <= u32::from(FULL_TURN_Q6)
    }

    /// RPM implied by the node count and the sample period.
    pub fn rpm(&self, cfg: &RplidarConfig) -> Option<f32> {
        let period = self.len as f32 * cfg.sample_period_s;
        (period > 0.0).then(|| 60.0 / period)
    }

    /// Plumbline's convention: counter-clockwise radians in arrival order (so angles fall), a
    /// beam per node, invalid for no return or beyond the configured range, timed by node.
    pub fn to_scan(&self, cfg: &RplidarConfig) -> Scan<N> {
        let mut scan = Scan::new(0.0);
        for (i, n) in self.nodes().iter().enumerate() {
            let angle = normalize_angle(-(f32::from(n.angle_q6) / 64.0).to_radians());
            let range = f32::from(n.distance_q2) / 4000.0;
            let mut beam = if n.distance_q2 > 0 && range < cfg.max_range_m {
                Beam::new(angle, range)
            } else {
                Beam::invalid(angle)
            };
            beam.time_offset_s = i as f32 * cfg.sample_period_s;
            // Cannot fail: at most N nodes were stored.
            let _ = scan.push(beam);
        }
        scan
    }
}

/// Bytes in, revolutions out. State: 7 bytes of window and one revolution (6 bytes a node:
/// about 4.8 KB for `N = 800`).
#[derive(Clone, Debug)]
pub struct RplidarDecoder<const N: usize> {
    /// A node, or a descriptor once the window starts `A5 5A`.
    window: [u8; DESCRIPTOR.len()],
    window_len: usize,
    in_sync: bool,
    current: RplidarRevolution<N>,
    stats: DecodeStats,
}

impl<const N: usize> Default for RplidarDecoder<N> {
    fn default() -> Self {
        Self {
            window: [0; DESCRIPTOR.len()],
            window_len: 0,
            in_sync: false,
            current: RplidarRevolution::default(),
            stats: DecodeStats::default(),
        }
    }
}

impl<const N: usize> RplidarDecoder<N> {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn stats(&self) -> DecodeStats {
        self.stats
    }

    pub fn push(&mut self, byte: u8) -> Option<RplidarRevolution<N>> {
        self.stats.bytes += 1;
        self.window[self.window_len] = byte;
        self.window_len += 1;
        // No node starts A5 5A (its check bit would be 0), so this is a descriptor or garbage.
        if self.window_len >= 2 && self.window[..2] == DESCRIPTOR[..2] {
            if self.window_len < DESCRIPTOR.len() {
                return None;
            }
            self.window_len = 0;
            self.in_sync = false;
            if self.window == DESCRIPTOR {
                return self.take(); // a new response: the old revolution ends here
            }
            self.stats.malformed += 1;
            self.stats.skipped_bytes += DESCRIPTOR.len() as u64;
            return None;
        }
        if self.window_len < NODE_LEN {
            return None;
        }
        let bytes = [
            self.window[0],
            self.window[1],
            self.window[2],
            self.window[3],
            self.window[4],
        ];
        let Some((node, start)) = Node::parse(bytes) else {
            if self.in_sync {
                self.stats.bad_checksum += 1;
                self.in_sync = false;
            }
            self.stats.skipped_bytes += 1;
            self.window.copy_within(1..NODE_LEN, 0);
            self.window_len -= 1;
            return None;
        };
        self.window_len = 0;
        self.in_sync = true;
        self.stats.packets_ok += 1;
        let closed = if start { self.take() } else { None };
        if self.current.len == 0 {
            self.current.starts_at_sync = start;
        }
        match self.current.nodes.get_mut(self.current.len) {
            Some(slot) => {
                *slot = node;
                self.current.len += 1;
            }
            None => self.stats.overflow += 1,
        }
        closed
    }

    /// Ends the stream: the revolution in progress, if any.
    pub fn finish(&mut self) -> Option<RplidarRevolution<N>> {
        self.take()
    }

    fn take(&mut self) -> Option<RplidarRevolution<N>> {
        if self.current.len == 0 {
            return None;
        }
        let rev = core::mem::take(&mut self.current);
        if !rev.is_plausible() {
            self.stats.implausible += 1;
            return None;
        }
        self.stats.revolutions += 1;
        Some(rev)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::test_encoders::{decode_all, rplidar_descriptor, rplidar_node};
    extern crate std;
    use std::vec::Vec;

    type A1 = RplidarDecoder<800>;

    fn decode(bytes: &[u8]) -> (Vec<RplidarRevolution<800>>, DecodeStats) {
        decode_all::<A1>(bytes)
    }

    /// `turns` revolutions of 360 nodes, one a degree, distance = 1000 mm + degree.
    fn stream(turns: usize) -> Vec<u8> {
        let mut out = rplidar_descriptor();
        for _ in 0..turns {
            for deg in 0..360u32 {
                out.extend(rplidar_node(deg == 0, 47, deg as f64, 1000.0 + deg as f64));
            }
        }
        out
    }

    #[test]
    fn descriptor_matches_the_protocol_document() {
        assert_eq!(rplidar_descriptor(), DESCRIPTOR);
    }

    #[test]
    fn revolutions_split_at_the_start_flag() {
        let (revs, stats) = decode(&stream(3));
        assert_eq!(revs.len(), 3);
        assert!(revs
            .iter()
            .all(|r| r.nodes().len() == 360 && r.starts_at_sync));
        assert_eq!(stats.packets_ok, 1080);
        assert_eq!(stats.skipped_bytes, 0);
        let n = revs[1].nodes()[90];
        assert_eq!(
            (n.quality, n.angle_q6, n.distance_q2),
            (47, 90 * 64, 1090 * 4)
        );
        let scan = revs[1].to_scan(&RplidarConfig::A1);
        // Clockwise 90 degrees is the device's right: -90 degrees counter-clockwise.
        assert!((scan.beams()[90].angle_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-5);
        assert!((scan.beams()[90].range_m - 1.090).abs() < 1e-6);
        assert!((scan.beams()[90].time_offset_s - 0.045).abs() < 1e-6);
        let rpm = revs[1].rpm(&RplidarConfig::A1).unwrap();
        assert!((rpm - 60.0 / 0.18).abs() < 1e-3);
    }

    #[test]
    fn garbage_in_the_middle_is_counted_and_skipped() {
        let clean = stream(2);
        let mut bytes = clean[..7 + 5 * 100].to_vec();
        bytes.extend_from_slice(&[0x00, 0x00, 0x00]); // check bits fail on every window
        bytes.extend_from_slice(&clean[7 + 5 * 100..]);
        let (revs, stats) = decode(&bytes);
        assert_eq!(stats.packets_ok, 720);
        assert_eq!((stats.bad_checksum, stats.skipped_bytes), (1, 3));
        assert_eq!(
            revs.iter().map(|r| r.nodes().len()).collect::<Vec<_>>(),
            [360, 360]
        );
    }

    #[test]
    fn zero_distance_is_an_invalid_beam_and_overflow_is_counted() {
        let mut bytes = rplidar_descriptor();
        for deg in 0..360 {
            let mm = if deg == 0 { 0.0 } else { 500.0 };
            bytes.extend(rplidar_node(deg == 0, 10, deg as f64, mm));
        }
        let (revs, _) = decode(&bytes);
        let scan = revs[0].to_scan(&RplidarConfig::A1);
        assert_eq!((scan.len(), scan.valid_count()), (360, 359));
        let mut d = RplidarDecoder::<200>::new();
        assert!(bytes.iter().all(|&b| d.push(b).is_none()));
        assert_eq!(d.stats().overflow, 160);
    }

    #[test]
    fn revolutions_an_rplidar_cannot_send_are_counted_not_handed_out() {
        // Too few nodes: a "revolution" of 50 nodes would be a 2400 rpm turn.
        let mut short = rplidar_descriptor();
        for deg in 0..50u32 {
            short.extend(rplidar_node(deg == 0, 47, deg as f64 * 7.2, 1000.0));
        }
        // Angles that jump: nodes 30 degrees apart.
        let mut jumpy = rplidar_descriptor();
        for k in 0..360u32 {
            jumpy.extend(rplidar_node(k == 0, 47, (k * 30 % 360) as f64, 1000.0));
        }
        // More than a turn: 1 degree a node for 400 nodes.
        let mut sweeping = rplidar_descriptor();
        for k in 0..400u32 {
            sweeping.extend(rplidar_node(k == 0, 47, (k % 360) as f64, 1000.0));
        }
        for bytes in [short, jumpy, sweeping] {
            let (revs, stats) = decode(&bytes);
            assert!(revs.is_empty());
            assert_eq!((stats.revolutions, stats.implausible), (0, 1));
        }
    }

    #[test]
    fn random_bytes_give_no_plausible_revolution() {
        // A fixed xorshift stream: reproducible, and as good as random for two check bits.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let bytes: Vec<u8> = (0..200_000)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x as u8
            })
            .collect();
        let (revs, stats) = decode(&bytes);
        assert!(stats.packets_ok > 10_000, "{stats:?}");
        assert!(stats.implausible > 1_000, "{stats:?}");
        assert_eq!(revs.len(), 0);
    }
}
