//! XV-11 revolutions: 360 one-degree readings placed by packet index, and their conversion to a
//! Plumbline [`Scan`].
//!
//! A revolution closes when (a) all 90 packets are in, (b) the index wraps (drops by more than
//! half a revolution, so a lost packet 89 or 0 still ends it), or (c) a packet's slot is already
//! filled. Rule (c) means a packet never overwrites another and never lands in a slot it does
//! not own: when a spinning-down device sends indices out of order (the tail of
//! `hand_in_box.bin`), the decoder hands out shorter revolutions with invalid beams instead of
//! merging two sweeps or shifting beams. Packets that arrive with a lower index without a wrap
//! are counted as `out_of_order`.
//!
//! A revolution whose mean speed field is outside [`MIN_RPM`, `MAX_RPM`] is not one an XV-11
//! sends (its motor is held near 300 rpm; spin-up and spin-down pass lower speeds) and is counted
//! as implausible instead of handed out. The packet checksum already refuses nearly all foreign
//! bytes; this catches the rest, and corrupt speed fields.

use super::xv11::{Packet, PacketParser, Reading, PACKETS_PER_REV, READINGS_PER_PACKET};
use super::DecodeStats;
use crate::scan::{Beam, Scan};

/// Readings in one revolution (one per degree).
pub const BEAMS: usize = PACKETS_PER_REV * READINGS_PER_PACKET;
const ALL_PACKETS: u128 = (1u128 << PACKETS_PER_REV) - 1;
const DEG_TO_RAD: f32 = core::f32::consts::PI / 180.0;
/// Slowest mean speed of a revolution handed out, rpm: below it the motor is stalled, not turning.
pub const MIN_RPM: f32 = 20.0;
/// Fastest, rpm: twice the speed the motor is regulated to.
pub const MAX_RPM: f32 = 600.0;
/// An index drop larger than this is a new revolution, a smaller one an out-of-order packet.
const WRAP_DROP: u8 = (PACKETS_PER_REV / 2) as u8;

/// One revolution as raw readings, 1.5 KB; convert with [`Revolution::to_scan`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Revolution {
    /// Raw readings by clockwise degree.
    readings: [[u8; 4]; BEAMS],
    /// Bit k set when packet k (degrees 4k..4k+3) arrived.
    present: u128,
    /// Sum of the packets' speed fields (1/64 RPM) and how many were summed; 0 when the device
    /// does not report a speed this decoder understands (old firmware).
    speed_q6_sum: u32,
    speed_count: u8,
    /// Stream offset of the first byte of the first packet received.
    pub first_offset: u64,
}

impl Default for Revolution {
    fn default() -> Self {
        Self {
            readings: [[0; 4]; BEAMS],
            present: 0,
            speed_q6_sum: 0,
            speed_count: 0,
            first_offset: 0,
        }
    }
}

impl Revolution {
    /// A complete revolution from 360 raw readings without a known speed (old firmware).
    pub fn from_readings(readings: [[u8; 4]; BEAMS], first_offset: u64) -> Self {
        Self {
            readings,
            present: ALL_PACKETS,
            speed_q6_sum: 0,
            speed_count: 0,
            first_offset,
        }
    }

    pub fn packets(&self) -> u32 {
        self.present.count_ones()
    }

    pub fn is_complete(&self) -> bool {
        self.present == ALL_PACKETS
    }

    pub fn has_packet(&self, index: usize) -> bool {
        index < PACKETS_PER_REV && self.present & (1 << index) != 0
    }

    /// The reading at a clockwise degree, `None` when its packet is missing.
    pub fn reading(&self, degree_cw: usize) -> Option<Reading> {
        let raw = self.readings.get(degree_cw)?;
        self.has_packet(degree_cw / READINGS_PER_PACKET)
            .then(|| Reading::from_bytes(*raw))
    }

    /// Mean motor speed over the packets received; `None` when the device reported none.
    pub fn rpm(&self) -> Option<f32> {
        (self.speed_count > 0)
            .then(|| self.speed_q6_sum as f32 / 64.0 / f32::from(self.speed_count))
    }

    fn add(&mut self, p: &Packet) {
        if self.present == 0 {
            self.first_offset = p.offset;
        }
        let k = usize::from(p.index);
        self.present |= 1 << k;
        self.readings[k * READINGS_PER_PACKET..(k + 1) * READINGS_PER_PACKET]
            .copy_from_slice(&p.readings);
        self.speed_q6_sum += u32::from(p.speed_q6);
        self.speed_count += 1;
    }

    /// Converts to Plumbline's convention: beam j sits at (j - 179) degrees counter-clockwise,
    /// so angles rise from -179 to +180 degrees and the scan is equally spaced (what CARMEN logs
    /// and matchers expect). Beam j holds the device's clockwise degree (179 - j) mod 360.
    /// A beam is valid when its packet arrived, the invalid flag is clear and the distance is
    /// non-zero; weak-signal readings stay valid (the device still measured them). Time offsets
    /// assume the mean RPM and count from degree 0, where the device starts its sweep; without
    /// a speed they are 0.
    pub fn to_scan(&self, stamp_s: f64) -> Scan<BEAMS> {
        let period_s = self.rpm().filter(|&r| r > 0.0).map(|r| 60.0 / r);
        let mut scan = Scan::new(stamp_s);
        for j in 0..BEAMS {
            // Already in (-pi, pi]; `min` only guards the rounding of +180 degrees.
            let angle = ((j as f32 - 179.0) * DEG_TO_RAD).min(core::f32::consts::PI);
            let cw = (179 + BEAMS - j) % BEAMS;
            let mut beam = match self.reading(cw) {
                Some(r) if !r.invalid && r.distance_mm > 0 => {
                    Beam::new(angle, f32::from(r.distance_mm) / 1000.0)
                }
                _ => Beam::invalid(angle),
            };
            beam.time_offset_s = period_s.map_or(0.0, |p| p * cw as f32 / BEAMS as f32);
            // Cannot fail: the scan holds exactly BEAMS beams.
            let _ = scan.push(beam);
        }
        scan
    }

    /// Angle of Plumbline beam 0 and the spacing, for writers of equally spaced scans.
    pub const START_ANGLE_DEG: f32 = -179.0;
    pub const INCREMENT_DEG: f32 = 1.0;
}

/// Places packets into revolutions (rules in the module docs). State: one [`Revolution`].
#[derive(Clone, Debug, Default)]
pub struct Assembler {
    current: Revolution,
    last_index: u8,
}

impl Assembler {
    /// Adds a packet; returns the revolution it closed, if any.
    pub fn add(&mut self, p: &Packet, stats: &mut DecodeStats) -> Option<Revolution> {
        let mut closed = None;
        if self.current.present != 0 {
            let wrapped = self.last_index > p.index.saturating_add(WRAP_DROP);
            if wrapped || self.current.has_packet(usize::from(p.index)) {
                closed = self.take(stats);
            } else if p.index < self.last_index {
                stats.out_of_order += 1;
            }
        }
        self.current.add(p);
        self.last_index = p.index;
        if self.current.is_complete() {
            closed = self.take(stats);
        }
        closed
    }

    /// Hands out what has arrived of the current revolution (end of stream), if anything.
    pub fn finish(&mut self, stats: &mut DecodeStats) -> Option<Revolution> {
        if self.current.present == 0 {
            return None;
        }
        self.take(stats)
    }

    /// Closes the current revolution: handed out, or counted as implausible.
    fn take(&mut self, stats: &mut DecodeStats) -> Option<Revolution> {
        let rev = core::mem::take(&mut self.current);
        if rev
            .rpm()
            .is_some_and(|rpm| !(MIN_RPM..=MAX_RPM).contains(&rpm))
        {
            stats.implausible += 1;
            return None;
        }
        stats.revolutions += 1;
        stats.missing_packets += PACKETS_PER_REV as u32 - rev.packets();
        Some(rev)
    }
}

/// Bytes in, revolutions out, for firmware 2.4 and later. State: a [`PacketParser`] and an
/// [`Assembler`], about 1.6 KB.
#[derive(Clone, Debug, Default)]
pub struct Xv11Decoder {
    parser: PacketParser,
    assembler: Assembler,
}

impl Xv11Decoder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one byte (a UART interrupt's view); returns the revolution it closed, if any.
    pub fn push(&mut self, byte: u8) -> Option<Revolution> {
        // Not `feed(&[byte])`: returning the 1.5 KB `Option` through it costs a copy per byte.
        let packet = self.parser.push(byte)?;
        self.assembler.add(&packet, &mut self.parser.stats)
    }

    /// Feeds bytes until a revolution closes: returns how many bytes were consumed and the
    /// revolution, if any (call again with the rest). The fast path for files and DMA buffers.
    pub fn feed(&mut self, bytes: &[u8]) -> (usize, Option<Revolution>) {
        let mut used = 0;
        while used < bytes.len() {
            let (n, packet) = self.parser.push_slice(&bytes[used..]);
            used += n;
            let closed = packet.and_then(|p| self.assembler.add(&p, &mut self.parser.stats));
            if closed.is_some() {
                return (used, closed);
            }
        }
        (used, None)
    }

    /// Ends the stream: the partial revolution, if any. Bytes of a torn last packet stay
    /// counted in `bytes` only.
    pub fn finish(&mut self) -> Option<Revolution> {
        self.assembler.finish(&mut self.parser.stats)
    }

    pub fn stats(&self) -> DecodeStats {
        self.parser.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::test_encoders::{decode_all, xv11_packet, xv11_reading, xv11_revolution};
    extern crate std;
    use std::vec::Vec;

    fn decode(bytes: &[u8]) -> (Vec<Revolution>, DecodeStats) {
        decode_all::<Xv11Decoder>(bytes)
    }

    #[test]
    fn full_revolution_maps_clockwise_degrees_to_ccw_angles() {
        let bytes = xv11_revolution(300 * 64, |deg| 1000 + deg as u16);
        let (revs, stats) = decode(&bytes);
        assert_eq!(revs.len(), 1);
        assert_eq!(stats.missing_packets, 0);
        let scan = revs[0].to_scan(0.0);
        assert_eq!(scan.len(), 360);
        // Clockwise degree 90 (device's right) is -90 degrees CCW: beam j = 179 - 90 = 89.
        let right = scan.beams()[89];
        assert!((right.angle_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-5);
        assert!((right.range_m - 1.090).abs() < 1e-6);
        // Degree 0 is straight ahead at beam 179 and starts the sweep.
        assert_eq!(scan.beams()[179].angle_rad, 0.0);
        assert_eq!(scan.beams()[179].time_offset_s, 0.0);
        // At 300 RPM a revolution lasts 0.2 s; clockwise degree 270 comes 0.15 s in.
        let left = scan.beams()[269];
        assert!((left.angle_rad - core::f32::consts::FRAC_PI_2).abs() < 1e-5);
        assert!((left.time_offset_s - 0.15).abs() < 1e-6);
        assert_eq!(scan.valid_count(), 360);
    }

    #[test]
    fn missing_packet_leaves_invalid_beams_at_its_angles() {
        let mut bytes = xv11_revolution(300 * 64, |_| 2000);
        bytes.drain(22 * 10..22 * 11); // packet 10: clockwise degrees 40..43
        let (revs, stats) = decode(&bytes);
        assert_eq!((revs.len(), stats.missing_packets), (1, 1));
        let scan = revs[0].to_scan(0.0);
        assert_eq!(scan.valid_count(), 356);
        for cw in 40..44 {
            let beam = scan.beams()[(179 + 360 - cw) % 360];
            assert!(!beam.valid);
            assert!((beam.angle_rad - (-(cw as f32)).to_radians()).abs() < 1e-5);
        }
        assert!(scan.beams()[(179 + 360 - 44) % 360].valid);
    }

    #[test]
    fn device_invalid_flag_makes_an_invalid_beam() {
        let mut r = [xv11_reading(500, false, 10); 4];
        r[2] = xv11_reading(0x21, true, 0);
        let (revs, _) = decode(&xv11_packet(0, 64 * 300, r));
        let scan = revs[0].to_scan(0.0);
        assert!(!scan.beams()[177].valid); // clockwise degree 2
        assert!(scan.beams()[178].valid);
    }

    #[test]
    fn wrap_closes_a_revolution_even_when_packet_zero_is_lost() {
        let mut bytes = xv11_revolution(300 * 64, |_| 1500);
        let second = xv11_revolution(300 * 64, |_| 1600);
        bytes.truncate(22 * 89); // packets 0..88
        bytes.extend_from_slice(&second[22..]); // next revolution from packet 1
        let (revs, stats) = decode(&bytes);
        assert_eq!(revs.len(), 2);
        assert_eq!((revs[0].packets(), revs[1].packets()), (89, 89));
        assert_eq!(stats.missing_packets, 2);
        assert_eq!(revs[1].reading(4).map(|r| r.distance_mm), Some(1600));
    }

    #[test]
    fn repeated_index_starts_a_new_revolution_instead_of_overwriting() {
        let p = |k, d| xv11_packet(k, 64 * 200, [xv11_reading(d, false, 1); 4]);
        let stream: Vec<u8> = [p(10, 100), p(40, 200), p(20, 300), p(40, 400)].concat();
        let (revs, stats) = decode(&stream);
        assert_eq!(revs.len(), 2);
        assert_eq!(stats.out_of_order, 1); // 20 after 40
        assert_eq!(revs[0].reading(160).map(|r| r.distance_mm), Some(200));
        assert_eq!(revs[1].reading(160).map(|r| r.distance_mm), Some(400));
        assert_eq!(revs[0].reading(80).map(|r| r.distance_mm), Some(300));
    }

    #[test]
    fn stream_stopping_mid_revolution_hands_out_the_partial_one() {
        let bytes = xv11_revolution(300 * 64, |_| 800);
        let (revs, stats) = decode(&bytes[..22 * 30 + 7]);
        assert_eq!(revs.len(), 1);
        assert_eq!(revs[0].packets(), 30);
        assert_eq!(revs[0].to_scan(0.0).valid_count(), 120);
        assert_eq!(stats.missing_packets, 60);
    }

    #[test]
    fn a_speed_the_motor_cannot_turn_at_is_implausible() {
        for rpm in [0u16, 10, 700, 1000] {
            let (revs, stats) = decode(&xv11_revolution(rpm * 64, |_| 1500));
            assert!(revs.is_empty(), "{rpm} rpm");
            assert_eq!((stats.implausible, stats.revolutions), (1, 0), "{rpm} rpm");
        }
        for rpm in [50u16, 300, 350] {
            let (revs, stats) = decode(&xv11_revolution(rpm * 64, |_| 1500));
            assert_eq!((revs.len(), stats.implausible), (1, 0), "{rpm} rpm");
        }
    }
}
