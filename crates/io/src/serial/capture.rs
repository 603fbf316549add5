//! Raw captures (the bytes a device sent) decoded into stamped CARMEN records.

use super::device::{DecodedScan, Device, DeviceDecoder};
use plumbline_core::lidar::DecodeStats;

/// What a decode saw; the `--json` summary of `plumbline lidar decode`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DecodeSummary {
    pub stats: DecodeStats,
    /// Median of the revolutions' mean RPM; `None` when the device reports no speed.
    pub rpm_median: Option<f32>,
    /// Invalid beams over all revolutions handed out (device-flagged, missing or no return).
    pub invalid_beams: u64,
}

impl DecodeSummary {
    pub fn new(scans: &[DecodedScan], stats: DecodeStats) -> Self {
        let mut rpm: Vec<f32> = scans.iter().filter_map(|s| s.rpm).collect();
        rpm.sort_by(f32::total_cmp);
        let rpm_median = (!rpm.is_empty()).then(|| {
            let mid = rpm.len() / 2;
            if rpm.len() % 2 == 1 {
                rpm[mid]
            } else {
                0.5 * (rpm[mid - 1] + rpm[mid])
            }
        });
        let invalid_beams = scans.iter().map(|s| s.invalid_beams() as u64).sum();
        Self {
            stats,
            rpm_median,
            invalid_beams,
        }
    }
}

/// Decodes a whole capture and stamps its records. Captures carry no clock, so a record's time
/// is the device's own clock where it sends one (URG), and otherwise the bytes before it at the
/// device's data rate (`DecodedScan::bytes_per_s`, each revolution at its own RPM), falling back
/// to the line rate at `baud` (10 bits a byte) for devices that give no rate (old XV-11).
pub fn decode_capture(
    device: Device,
    bytes: &[u8],
    baud: u32,
) -> (Vec<DecodedScan>, DecodeSummary) {
    let mut decoder = DeviceDecoder::new(device);
    let mut scans: Vec<DecodedScan> = bytes.iter().filter_map(|&b| decoder.push(b)).collect();
    scans.extend(decoder.finish());
    let line_rate = f64::from(baud.max(1)) / 10.0;
    let (mut t, mut last_offset, mut rate) = (0.0, 0, line_rate);
    for s in &mut scans {
        t += s.first_offset.saturating_sub(last_offset) as f64 / rate;
        last_offset = s.first_offset;
        rate = s.bytes_per_s.filter(|r| *r > 0.0).unwrap_or(line_rate);
        s.stamp(s.device_time_s.unwrap_or(t));
    }
    let summary = DecodeSummary::new(&scans, decoder.stats());
    (scans, summary)
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
        let s = DecodeSummary::new(
            &[scan(Some(3.0)), scan(Some(1.0)), scan(None)],
            DecodeStats::default(),
        );
        assert_eq!(s.rpm_median, Some(2.0));
        assert_eq!(s.invalid_beams, 3);
        assert_eq!(
            DecodeSummary::new(&[scan(None)], DecodeStats::default()).rpm_median,
            None
        );
    }

    #[test]
    fn garbage_decodes_to_nothing_with_every_byte_skipped() {
        let bytes: Vec<u8> = (0..5000u32).map(|i| (i * 7 % 251) as u8 & 0x7F).collect();
        let (scans, summary) = decode_capture(Device::Xv11, &bytes, 115_200);
        assert!(scans.is_empty());
        assert_eq!(summary.stats.skipped_bytes, 5000);
    }

    #[test]
    fn urg_reply_becomes_an_equally_spaced_record_from_step_44() {
        // GS, steps 44..=45: two values "CB" = 1234 mm (SCIP 2.0 spec example), hand-summed.
        let (scans, summary) =
            decode_capture(Device::Urg, b"GS0044004500\n00P\n00000\nCBCB:\n\n", 115_200);
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
        let (scans, summary) = decode_capture(Device::Rplidar, &bytes, 115_200);
        assert_eq!((scans.len(), summary.stats.packets_ok), (1, 360));
        let rec = &scans[0].record;
        assert_eq!(rec.beam_count(), 360);
        assert_eq!((rec.valid[179], rec.ranges_m[179]), (true, 1.0));
        assert_eq!((rec.valid[89], rec.ranges_m[89]), (true, 1.09)); // -90 deg: the right
        assert_eq!(scans[0].invalid_beams(), 358);
    }
}
