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

/// Decodes a whole capture. Records are stamped by byte position at `baud` (10 bits a byte on
/// an 8N1 line): captures carry no clock, and the device streams continuously, so this is the
/// time since the capture began, to within the device's own pauses.
pub fn decode_capture(
    device: Device,
    bytes: &[u8],
    baud: u32,
) -> (Vec<DecodedScan>, DecodeSummary) {
    let mut decoder = DeviceDecoder::new(device);
    let mut scans: Vec<DecodedScan> = bytes.iter().filter_map(|&b| decoder.push(b)).collect();
    scans.extend(decoder.finish());
    let bytes_per_s = f64::from(baud.max(1)) / 10.0;
    for s in &mut scans {
        s.stamp(s.first_offset as f64 / bytes_per_s);
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
}
