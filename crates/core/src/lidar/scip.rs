//! Hokuyo SCIP 2.0 replies (URG-04LX and kin): MD/MS streamed scans and GD/GS single scans.
//!
//! A reply is lines ended by LF and closed by an empty line: the command echo, a status line
//! (`00` accepted, `99` scan data follows an MD/MS stream, anything else an error code), a
//! timestamp line (4 characters, 24-bit milliseconds), then data lines of up to 64 characters.
//! Every line after the echo ends in a sum character: the low 6 bits of the byte sum of the line
//! plus 0x30. Range values are 2 or 3 characters of 6 bits each (character minus 0x30) and may
//! straddle lines (specification C-42-03320B, sections 6-8).
//!
//! A scan is handed out only when every line's sum is right and the value count matches the
//! echoed step range; otherwise the whole scan is dropped and counted, never shifted. Replies to
//! other commands (BM, QT, PP, VV...) are passed over.

use super::scip_command::Encoding;
use super::DecodeStats;
use crate::geom::normalize_angle;
use crate::scan::{Beam, Scan};

/// Longest line kept: an echo with its 16-character string, or 64 data characters plus sum.
const MAX_LINE: usize = 80;

/// What a scan's geometry and validity depend on; `URG_04LX` holds the sensor's `PP` answers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UrgConfig {
    /// Steps in a full turn (`ARES`).
    pub steps_per_rev: u16,
    /// The step pointing along body x (`AFRT`).
    pub front_step: u16,
    /// One mirror revolution (60 / `SCAN` rpm), for per-beam time.
    pub scan_period_s: f32,
    /// Values below `DMIN` are error codes, not ranges.
    pub min_range_mm: u32,
    /// `DMAX`: longer values are not trusted.
    pub max_range_mm: u32,
}

impl UrgConfig {
    pub const URG_04LX: UrgConfig = UrgConfig {
        steps_per_rev: 1024,
        front_step: 384,
        scan_period_s: 0.1,
        min_range_mm: 20,
        max_range_mm: 5600,
    };

    /// Angle of a (possibly fractional) step: Hokuyo steps turn counter-clockwise.
    pub fn step_angle_rad(&self, step: f32) -> f32 {
        let per_step = core::f32::consts::TAU / f32::from(self.steps_per_rev);
        normalize_angle((step - f32::from(self.front_step)) * per_step)
    }
}

/// One scan's raw values, at most `N` (769 covers every URG-04LX step).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScipScan<const N: usize> {
    ranges_mm: [u32; N],
    len: usize,
    pub start_step: u16,
    /// Steps merged into each value (at least 1).
    pub cluster: u16,
    /// The sensor's 24-bit millisecond clock at the scan.
    pub timestamp_ms: u32,
}

impl<const N: usize> Default for ScipScan<N> {
    fn default() -> Self {
        Self {
            ranges_mm: [0; N],
            len: 0,
            start_step: 0,
            cluster: 1,
            timestamp_ms: 0,
        }
    }
}

impl<const N: usize> ScipScan<N> {
    pub fn ranges_mm(&self) -> &[u32] {
        &self.ranges_mm[..self.len]
    }

    /// The step a value's beam points at: the centre of its cluster.
    pub fn value_step(&self, i: usize) -> f32 {
        let c = f32::from(self.cluster);
        f32::from(self.start_step) + i as f32 * c + (c - 1.0) / 2.0
    }

    /// Plumbline's convention: counter-clockwise radians, invalid outside `[min, max]` mm,
    /// stamped with the sensor clock, per-beam time from the mirror's angular speed.
    pub fn to_scan(&self, cfg: &UrgConfig) -> Scan<N> {
        let mut scan = Scan::new(f64::from(self.timestamp_ms) / 1000.0);
        let first = self.value_step(0);
        for (i, &mm) in self.ranges_mm().iter().enumerate() {
            let step = self.value_step(i);
            let angle = cfg.step_angle_rad(step);
            let mut beam = if (cfg.min_range_mm..=cfg.max_range_mm).contains(&mm) {
                Beam::new(angle, mm as f32 / 1000.0)
            } else {
                Beam::invalid(angle)
            };
            beam.time_offset_s = (step - first) / f32::from(cfg.steps_per_rev) * cfg.scan_period_s;
            // Cannot fail: at most N values were stored.
            let _ = scan.push(beam);
        }
        scan
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Waiting for a command echo.
    Echo,
    Status,
    Timestamp,
    Data,
    /// Passing over lines until the empty line that ends a reply.
    Skip,
}

/// What the echo of a scan command told us to expect.
#[derive(Clone, Copy, Debug, Default)]
struct Request {
    streamed: bool,
    chars: u8,
    start: u16,
    end: u16,
    cluster: u16,
    values: usize,
}

/// The SCIP 2.0 sum character of a line's bytes.
pub fn line_sum(bytes: &[u8]) -> u8 {
    (bytes.iter().fold(0u32, |s, &b| s + u32::from(b)) & 0x3F) as u8 + 0x30
}

fn decimal(bytes: &[u8]) -> Option<u16> {
    bytes.iter().try_fold(0u16, |v, &b| {
        b.is_ascii_digit().then(|| v * 10 + u16::from(b - b'0'))
    })
}

fn parse_echo(line: &[u8]) -> Option<Request> {
    let (streamed, chars) = match line.get(..2)? {
        b"MD" => (true, Encoding::ThreeChar),
        b"MS" => (true, Encoding::TwoChar),
        b"GD" => (false, Encoding::ThreeChar),
        b"GS" => (false, Encoding::TwoChar),
        _ => return None,
    };
    let params = line.split(|&b| b == b';').next()?;
    let want = if streamed { 15 } else { 12 };
    if params.len() != want {
        return None;
    }
    let start = decimal(&params[2..6])?;
    let end = decimal(&params[6..10])?;
    let cluster = decimal(&params[10..12])?.max(1);
    if start > end {
        return None;
    }
    // Clusters covering steps start..=end: ceil((end - start + 1) / cluster).
    let values = usize::from((end - start) / cluster) + 1;
    Some(Request {
        streamed,
        chars: chars.chars() as u8,
        start,
        end,
        cluster,
        values,
    })
}

/// Bytes in, scans out, for a sensor of `N` steps (URG-04LX: 769; replies for steps beyond are
/// implausible). State: one line, one [`ScipScan`] (4 bytes a value), 3.2 KB for `N = 769`.
#[derive(Clone, Debug)]
pub struct ScipDecoder<const N: usize> {
    line: [u8; MAX_LINE],
    line_len: usize,
    line_overflow: bool,
    state: State,
    request: Request,
    acc: u32,
    acc_chars: u8,
    scan: ScipScan<N>,
    /// The last error status a sensor replied with (`None` until one arrives).
    pub last_error_status: Option<[u8; 2]>,
    stats: DecodeStats,
}

impl<const N: usize> Default for ScipDecoder<N> {
    fn default() -> Self {
        Self {
            line: [0; MAX_LINE],
            line_len: 0,
            line_overflow: false,
            state: State::Echo,
            request: Request::default(),
            acc: 0,
            acc_chars: 0,
            scan: ScipScan::default(),
            last_error_status: None,
            stats: DecodeStats::default(),
        }
    }
}

impl<const N: usize> ScipDecoder<N> {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn stats(&self) -> DecodeStats {
        self.stats
    }

    /// Ends the stream. Always `None`: a scan is complete only at the empty line closing its
    /// reply, so a reply cut short is dropped (its bytes stay counted in `bytes`).
    pub fn finish(&mut self) -> Option<ScipScan<N>> {
        None
    }

    pub fn push(&mut self, byte: u8) -> Option<ScipScan<N>> {
        self.stats.bytes += 1;
        if byte != b'\n' {
            match self.line.get_mut(self.line_len) {
                Some(slot) => {
                    *slot = byte;
                    self.line_len += 1;
                }
                None => self.line_overflow = true,
            }
            return None;
        }
        let len = core::mem::take(&mut self.line_len);
        if core::mem::take(&mut self.line_overflow) {
            self.fault_malformed();
            return None;
        }
        if len == 0 {
            return self.end_of_reply();
        }
        let line = self.line;
        self.on_line(&line[..len]);
        None
    }

    fn fault_malformed(&mut self) {
        self.stats.malformed += 1;
        self.state = State::Skip;
    }

    /// Checks a line's sum; counts and skips the reply when it is wrong.
    fn summed<'a>(&mut self, line: &'a [u8]) -> Option<&'a [u8]> {
        let (&sum, body) = line.split_last()?;
        if line_sum(body) != sum {
            self.stats.bad_checksum += 1;
            self.state = State::Skip;
            return None;
        }
        self.stats.packets_ok += 1;
        Some(body)
    }

    fn on_line(&mut self, line: &[u8]) {
        match self.state {
            State::Echo => match parse_echo(line) {
                Some(req) if req.values > N => {
                    self.stats.overflow += 1;
                    self.state = State::Skip;
                }
                Some(req) if usize::from(req.end) >= N => {
                    self.stats.implausible += 1;
                    self.state = State::Skip;
                }
                Some(req) => {
                    self.request = req;
                    self.state = State::Status;
                }
                None => self.state = State::Skip,
            },
            State::Status => {
                let Some(status) = self.summed(line) else {
                    return;
                };
                self.state = match (status, self.request.streamed) {
                    (b"99", true) | (b"00", false) => State::Timestamp,
                    (b"00", true) => State::Skip, // the stream's acknowledgement, no data
                    (&[a, b], _) => {
                        self.last_error_status = Some([a, b]);
                        self.stats.malformed += 1;
                        State::Skip
                    }
                    _ => {
                        self.stats.malformed += 1;
                        State::Skip
                    }
                };
            }
            State::Timestamp => {
                let Some(body) = self.summed(line) else {
                    return;
                };
                if body.len() != 4 {
                    return self.fault_malformed();
                }
                self.scan.len = 0;
                self.scan.start_step = self.request.start;
                self.scan.cluster = self.request.cluster;
                self.scan.timestamp_ms = 0;
                self.acc = 0;
                self.acc_chars = 0;
                for &c in body {
                    let Some(v) = c.checked_sub(0x30).filter(|v| *v < 64) else {
                        return self.fault_malformed();
                    };
                    self.scan.timestamp_ms = self.scan.timestamp_ms << 6 | u32::from(v);
                }
                self.state = State::Data;
            }
            State::Data => {
                let Some(body) = self.summed(line) else {
                    return;
                };
                for &c in body {
                    if !self.take_char(c) {
                        return self.fault_malformed();
                    }
                }
            }
            State::Skip => {}
        }
    }

    /// Adds one encoded character; false when it is not a SCIP data character or there are
    /// more values than the echo announced.
    fn take_char(&mut self, c: u8) -> bool {
        let Some(v) = c.checked_sub(0x30).filter(|v| *v < 64) else {
            return false;
        };
        self.acc = self.acc << 6 | u32::from(v);
        self.acc_chars += 1;
        if self.acc_chars < self.request.chars {
            return true;
        }
        let value = core::mem::take(&mut self.acc);
        self.acc_chars = 0;
        if self.scan.len >= self.request.values {
            return false;
        }
        self.scan.ranges_mm[self.scan.len] = value;
        self.scan.len += 1;
        true
    }

    fn end_of_reply(&mut self) -> Option<ScipScan<N>> {
        let state = core::mem::replace(&mut self.state, State::Echo);
        if state != State::Data {
            if matches!(state, State::Status | State::Timestamp) {
                self.stats.malformed += 1;
            }
            return None;
        }
        if self.scan.len != self.request.values || self.acc_chars != 0 {
            self.stats.malformed += 1;
            return None;
        }
        self.stats.revolutions += 1;
        Some(self.scan.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::test_encoders::{decode_all, scip_encode, scip_scan_reply};
    extern crate std;
    use std::vec::Vec;

    type Urg = ScipDecoder<769>;

    fn decode(bytes: &[u8]) -> (Vec<ScipScan<769>>, DecodeStats) {
        decode_all::<Urg>(bytes)
    }

    #[test]
    fn specification_examples_decode() {
        // Section 6: 1234 mm is "CB" in 2 characters, 5432 mm is "1Dh" in 3.
        assert_eq!(scip_encode(1234, 2), b"CB");
        assert_eq!(scip_encode(5432, 3), b"1Dh");
        // Section 7: status "00" carries sum 'P', "99" carries 'b'; PP's "DMIN:20" carries '4'.
        assert_eq!(line_sum(b"00"), b'P');
        assert_eq!(line_sum(b"99"), b'b');
        assert_eq!(line_sum(b"DMIN:20"), b'4');
        // Whole replies written out by hand (sums: "0000" -> '0', "CBCB" -> ':', "1Dh" -> 'M').
        let (scans, stats) =
            decode(b"GS0044004500\n00P\n00000\nCBCB:\n\nGD0044004400\n00P\n00000\n1DhM\n\n");
        assert_eq!(scans.len(), 2);
        assert_eq!(scans[0].ranges_mm(), [1234, 1234]);
        assert_eq!(scans[1].ranges_mm(), [5432]);
        assert_eq!(
            (stats.packets_ok, stats.bad_checksum, stats.malformed),
            (6, 0, 0)
        );
        // One character too many for the announced steps: the scan is dropped, not cut.
        let (scans, stats) = decode(b"GS0044004500\n00P\n00000\nCBCB1k\n\n");
        assert!(scans.is_empty());
        assert_eq!(stats.malformed, 1);
    }

    #[test]
    fn md_stream_of_three_character_values_spanning_lines() {
        let values: Vec<u32> = (0..682).map(|i| 20 + i * 7).collect();
        let ack = b"MD0044072500000\n00P\n\n";
        let scan = scip_scan_reply(b"MD0044072500000", b"99", 0x123456, &values, 3);
        let stream = [&ack[..], &scan, &scan].concat();
        let (scans, stats) = decode(&stream);
        assert_eq!(scans.len(), 2);
        assert_eq!(scans[0].ranges_mm(), &values[..]);
        assert_eq!(scans[0].timestamp_ms, 0x123456);
        assert_eq!((stats.bad_checksum, stats.malformed), (0, 0));
        let s = scans[0].to_scan(&UrgConfig::URG_04LX);
        assert_eq!(s.len(), 682);
        // Step 384 is straight ahead; steps rise counter-clockwise by 360/1024 degrees.
        assert!(s.beams()[384 - 44].angle_rad.abs() < 1e-6);
        let step_rad = core::f32::consts::TAU / 1024.0;
        assert!((s.beams()[384 - 44 + 256].angle_rad - 256.0 * step_rad).abs() < 1e-5);
        assert!((s.beams()[681].time_offset_s - 681.0 / 1024.0 * 0.1).abs() < 1e-6);
        // Beyond DMAX (5600 mm) is invalid.
        assert_eq!(
            s.valid_count(),
            values.iter().filter(|&&v| v <= 5600).count()
        );
    }

    #[test]
    fn gd_with_clusters_places_beams_at_cluster_centres() {
        let values = [1000, 2000, 15, 4000];
        let reply = scip_scan_reply(b"GD0100011103", b"00", 7, &values, 3);
        let (scans, _) = decode(&reply);
        assert_eq!(scans.len(), 1);
        assert_eq!(scans[0].value_step(1), 104.0);
        let s = scans[0].to_scan(&UrgConfig::URG_04LX);
        assert!(!s.beams()[2].valid, "15 mm is an error code");
        assert!((s.beams()[0].angle_rad - UrgConfig::URG_04LX.step_angle_rad(101.0)).abs() < 1e-6);
    }

    #[test]
    fn any_single_corrupted_byte_drops_the_scan_or_leaves_it_exact() {
        use proptest::prelude::*;
        use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
        let values: Vec<u32> = (0..682).map(|i| 300 + (i * 37) % 5000).collect();
        let reply = scip_scan_reply(b"MD0044072500000", b"99", 4242, &values, 3);
        let (clean, _) = decode(&reply);
        assert_eq!(clean.len(), 1);
        let config = Config {
            cases: 2000,
            failure_persistence: None,
            ..Config::default()
        };
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[5; 32]));
        runner
            .run(&(0..reply.len(), 1u8..=255), |(pos, flip)| {
                let mut bad = reply.clone();
                bad[pos] ^= flip;
                let (scans, _) = decode(&bad);
                // The 6-bit line sum alone misses changes of 64; the character range check
                // catches those, so a corrupted scan can never come out altered.
                prop_assert!(scans.iter().all(|s| *s == clean[0]));
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn bad_line_sum_drops_the_scan_and_the_next_scan_decodes() {
        let values = [500u32; 100];
        let good = scip_scan_reply(b"MS0000009900000", b"99", 1, &values, 2);
        let mut bad = good.clone();
        let pos = bad.len() - 10;
        bad[pos] ^= 0x01;
        let (scans, stats) = decode(&[bad, good].concat());
        assert_eq!(scans.len(), 1);
        assert_eq!(stats.bad_checksum, 1);
    }

    #[test]
    fn error_status_is_reported_and_other_replies_are_passed_over() {
        let stream = [&b"VV\n00P\nVEND:Hokuyo;[\n\nMD0044072500000\n0Ee\n\n"[..]].concat();
        let mut d = Urg::new();
        assert!(stream.iter().all(|&b| d.push(b).is_none()));
        assert_eq!(d.last_error_status, Some(*b"0E"));
        assert_eq!(d.stats().malformed, 1);
    }

    #[test]
    fn more_steps_than_the_buffer_holds_is_an_overflow_not_a_panic() {
        let values = [500u32; 20];
        let reply = scip_scan_reply(b"GD0000001900", b"00", 1, &values, 3);
        let mut d = ScipDecoder::<10>::new();
        assert!(reply.iter().all(|&b| d.push(b).is_none()));
        assert_eq!(d.stats().overflow, 1);
    }
}
