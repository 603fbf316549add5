//! Raw captures (the bytes a device sent) decoded into stamped CARMEN records.

use super::device::{DecodedScan, Device, DeviceDecoder};
use plumbline_core::lidar::DecodeStats;
use std::io::{self, Read};

/// What a decode saw; the `--json` summary of `plumbline lidar decode`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DecodeSummary {
    pub stats: DecodeStats,
    /// Median of the revolutions' mean RPM; `None` when the device reports no speed.
    pub rpm_median: Option<f32>,
    /// Invalid beams over all revolutions handed out (device-flagged, missing or no return).
    pub invalid_beams: u64,
}

/// What the summary needs from each revolution, kept as revolutions pass so no decode holds its
/// scans: one RPM per revolution (for the median) and a count.
#[derive(Clone, Debug, Default)]
pub struct SummaryTally {
    rpms: Vec<f32>,
    invalid_beams: u64,
}

impl SummaryTally {
    pub fn add(&mut self, scan: &DecodedScan) {
        self.rpms.extend(scan.rpm);
        self.invalid_beams += scan.invalid_beams() as u64;
    }

    pub fn summary(&self, stats: DecodeStats) -> DecodeSummary {
        let mut rpm = self.rpms.clone();
        rpm.sort_by(f32::total_cmp);
        let rpm_median = (!rpm.is_empty()).then(|| {
            let mid = rpm.len() / 2;
            if rpm.len() % 2 == 1 {
                rpm[mid]
            } else {
                0.5 * (rpm[mid - 1] + rpm[mid])
            }
        });
        DecodeSummary {
            stats,
            rpm_median,
            invalid_beams: self.invalid_beams,
        }
    }
}

/// A capture may open with noise (a device booting, a port opened mid-packet), but this many
/// bytes without one valid frame means the device or the baud rate is wrong, or the file is
/// not a capture at all (`/dev/zero`); decoding stops there instead of reading on forever.
pub const MAX_BYTES_WITHOUT_FRAME: u64 = 1 << 20;

/// Why a capture could not be decoded.
#[derive(Debug)]
pub enum CaptureError {
    Read {
        name: String,
        source: io::Error,
    },
    NoFrame {
        name: String,
        device: Device,
        from_byte: u64,
    },
}

impl std::fmt::Display for CaptureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CaptureError::Read { name, source } => write!(f, "{name}: cannot read: {source}"),
            CaptureError::NoFrame {
                name,
                device,
                from_byte,
            } => write!(
                f,
                "{name}: {} bytes from byte {from_byte} on hold no valid {device} frame; \
                 decoding stopped (wrong --device, wrong baud rate, or not a capture?)",
                MAX_BYTES_WITHOUT_FRAME
            ),
        }
    }
}

impl std::error::Error for CaptureError {}

/// Decodes a capture as it is read, through a fixed buffer, handing each stamped scan to
/// `on_scan` as soon as it is complete; `on_scan` returns `false` to stop early. Captures carry
/// no clock, so a record's time is the device's own clock where it sends one (URG), and
/// otherwise the bytes before it at the device's data rate (`DecodedScan::bytes_per_s`, each
/// revolution at its own RPM), falling back to the line rate at `baud` (10 bits a byte) for
/// devices that give no rate (old XV-11).
pub fn decode_stream<R: Read, E: From<CaptureError>>(
    device: Device,
    mut reader: R,
    name: &str,
    baud: u32,
    mut on_scan: impl FnMut(DecodedScan) -> Result<bool, E>,
) -> Result<DecodeSummary, E> {
    let mut decoder = DeviceDecoder::new(device);
    let mut tally = SummaryTally::default();
    let line_rate = f64::from(baud.max(1)) / 10.0;
    let (mut t, mut last_offset, mut rate) = (0.0, 0, line_rate);
    let mut stamp = |mut s: DecodedScan, tally: &mut SummaryTally| {
        t += s.first_offset.saturating_sub(last_offset) as f64 / rate;
        last_offset = s.first_offset;
        rate = s.bytes_per_s.filter(|r| *r > 0.0).unwrap_or(line_rate);
        s.stamp(s.device_time_s.unwrap_or(t));
        tally.add(&s);
        s
    };
    let mut buf = vec![0u8; 64 << 10];
    let (mut last_ok, mut good_since) = (0, 0);
    loop {
        let n = match reader.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(source) => {
                let name = name.to_string();
                return Err(CaptureError::Read { name, source }.into());
            }
        };
        for &b in &buf[..n] {
            if let Some(scan) = decoder.push(b) {
                if !on_scan(stamp(scan, &mut tally))? {
                    return Ok(tally.summary(decoder.stats()));
                }
            }
        }
        let stats = decoder.stats();
        if stats.packets_ok != last_ok {
            (last_ok, good_since) = (stats.packets_ok, stats.bytes);
        } else if stats.bytes - good_since > MAX_BYTES_WITHOUT_FRAME {
            return Err(CaptureError::NoFrame {
                name: name.to_string(),
                device,
                from_byte: good_since,
            }
            .into());
        }
    }
    if let Some(scan) = decoder.finish() {
        on_scan(stamp(scan, &mut tally))?;
    }
    Ok(tally.summary(decoder.stats()))
}

/// Decodes a capture held in memory and keeps its scans (tests, fuzzing, small captures).
pub fn decode_capture(
    device: Device,
    bytes: &[u8],
    baud: u32,
) -> Result<(Vec<DecodedScan>, DecodeSummary), CaptureError> {
    let mut scans = Vec::new();
    let summary = decode_stream(device, bytes, "capture", baud, |s| {
        scans.push(s);
        Ok::<_, CaptureError>(true)
    })?;
    Ok((scans, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_even_and_odd_counts_and_none_without_speed() {
        let scan = |rpm| DecodedScan {
            record: crate::carmen::LaserRecord::new(0.0, 0.0, 0.1, 5.0, vec![1.0, 0.0]),
            rpm,
            first_offset: 0,
            bytes_per_s: None,
            device_time_s: None,
        };
        let mut tally = SummaryTally::default();
        for s in [scan(Some(3.0)), scan(Some(1.0)), scan(None)] {
            tally.add(&s);
        }
        let s = tally.summary(DecodeStats::default());
        assert_eq!(s.rpm_median, Some(2.0));
        assert_eq!(s.invalid_beams, 3);
        let mut none = SummaryTally::default();
        none.add(&scan(None));
        assert_eq!(none.summary(DecodeStats::default()).rpm_median, None);
    }

    #[test]
    fn garbage_decodes_to_nothing_with_every_byte_skipped() {
        let bytes: Vec<u8> = (0..5000u32).map(|i| (i * 7 % 251) as u8 & 0x7F).collect();
        let (scans, summary) = decode_capture(Device::Xv11, &bytes, 115_200).unwrap();
        assert!(scans.is_empty());
        assert_eq!(summary.stats.skipped_bytes, 5000);
    }

    #[test]
    fn endless_noise_stops_after_the_bound_with_bounded_memory() {
        let zeros = std::io::repeat(0).take(1 << 30);
        let err = decode_stream(Device::Xv11, zeros, "zeros", 115_200, |_| {
            Ok::<_, CaptureError>(true)
        })
        .unwrap_err();
        assert!(
            matches!(err, CaptureError::NoFrame { from_byte: 0, .. }),
            "{err}"
        );
    }

    #[test]
    fn urg_reply_becomes_an_equally_spaced_record_from_step_44() {
        // GS, steps 44..=45: two values "CB" = 1234 mm (SCIP 2.0 spec example), hand-summed.
        let (scans, summary) =
            decode_capture(Device::Urg, b"GS0044004500\n00P\n00000\nCBCB:\n\n", 115_200).unwrap();
        assert_eq!((scans.len(), summary.stats.revolutions), (1, 1));
        let rec = &scans[0].record;
        assert_eq!(rec.ranges_m, [1.234, 1.234]);
        assert!((rec.start_angle_rad.to_degrees() + 119.53125).abs() < 1e-4);
        assert!((rec.increment_rad.to_degrees() - 0.3515625).abs() < 1e-6);
    }

    #[test]
    fn rplidar_nodes_land_in_whole_degree_bins() {
        // A standard-scan response descriptor, then a node a degree clockwise, quality 47; only
        // 0 deg (1000 mm) and 90 deg (1090 mm) return.
        let mut bytes = vec![0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
        for deg in 0..360u16 {
            let start = u8::from(deg == 0);
            let angle = (deg * 64) << 1 | 1;
            let mm: u16 = match deg {
                0 => 1000,
                90 => 1090,
                _ => 0,
            };
            bytes.push(47 << 2 | (1 - start) << 1 | start);
            bytes.extend((angle).to_le_bytes());
            bytes.extend((mm * 4).to_le_bytes());
        }
        let (scans, summary) = decode_capture(Device::Rplidar, &bytes, 115_200).unwrap();
        assert_eq!((scans.len(), summary.stats.packets_ok), (1, 360));
        let rec = &scans[0].record;
        assert_eq!(rec.beam_count(), 360);
        assert_eq!((rec.valid[179], rec.ranges_m[179]), (true, 1.0));
        assert_eq!((rec.valid[89], rec.ranges_m[89]), (true, 1.09)); // -90 deg: the right
        assert_eq!(scans[0].invalid_beams(), 358);
    }

    /// At most `chunk` bytes a read, as a port delivers them.
    struct Chunked<'a>(&'a [u8], usize);

    impl Read for Chunked<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let n = self.0.len().min(buf.len()).min(self.1);
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    proptest::proptest! {
        #[test]
        fn chunking_changes_nothing(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..6000),
            chunk in 1usize..300,
            pick in 0usize..4,
        ) {
            let device = [Device::Xv11, Device::Xv11Old, Device::Urg, Device::Rplidar][pick];
            // Valid XV-11 packets spliced in, so whole revolutions occur too.
            let mut input = std::fs::read(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../data/captures/neato-xv11/hand_in_box.bin"
            ))
            .map(|c| c[..4000].to_vec())
            .unwrap_or_default();
            input.extend(&bytes);
            let (whole, a) = decode_capture(device, &input, 115_200).unwrap();
            let mut streamed = Vec::new();
            let b = decode_stream(device, Chunked(&input, chunk), "t", 115_200, |s| {
                streamed.push(s);
                Ok::<_, CaptureError>(true)
            })
            .unwrap();
            proptest::prop_assert_eq!(whole, streamed);
            proptest::prop_assert_eq!(a, b);
        }
    }
}
