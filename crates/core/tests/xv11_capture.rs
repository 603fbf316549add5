//! The real XV-11 capture `hand_in_box.bin` (firmware >= 2.4) through the decoder, with the
//! counts found independently (see `data/captures/neato-xv11/SOURCE.md`).

use plumbline_core::lidar::xv11_revolution::{Revolution, Xv11Decoder};
use plumbline_core::lidar::DecodeStats;

mod common;
use common::{capture, decode};

fn decode_capture() -> (Vec<Revolution>, DecodeStats) {
    decode::<Xv11Decoder>(&capture("hand_in_box.bin"))
}

#[test]
fn packet_counts_match_the_independent_count() {
    let (_, stats) = decode_capture();
    assert_eq!(stats.bytes, 252_146);
    assert_eq!(stats.packets_ok, 11_451);
    assert_eq!(stats.bad_checksum, 1);
}

#[test]
fn every_good_packet_lands_in_exactly_one_revolution() {
    let (revs, stats) = decode_capture();
    let placed: u32 = revs.iter().map(Revolution::packets).sum();
    assert_eq!(placed, stats.packets_ok);
    assert_eq!(stats.revolutions as usize, revs.len());
    assert_eq!(stats.missing_packets, 90 * stats.revolutions - placed);
    // 126 packets carry index 0 (A0); each opens a different revolution.
    assert_eq!(revs.iter().filter(|r| r.has_packet(0)).count(), 126);
}

#[test]
fn in_order_part_gives_full_revolutions_and_the_tail_is_split_not_merged() {
    let (revs, stats) = decode_capture();
    // The capture starts mid-revolution at packet 58.
    assert_eq!(revs[0].packets(), 32);
    assert!(!revs[0].has_packet(57) && revs[0].has_packet(58));
    let complete = revs.iter().filter(|r| r.is_complete()).count();
    assert_eq!(complete, 120);
    assert_eq!(revs.len(), 161);
    // The spin-down tail arrives out of order; those packets are counted. 161 and 232 were also
    // found by a separate script applying the rules in `xv11_revolution`'s docs.
    assert_eq!(stats.out_of_order, 232);
    // Steady part: RPM near 297; the speed field spans spin-up and spin-down.
    let rpm: Vec<f32> = revs.iter().filter_map(Revolution::rpm).collect();
    assert!((rpm[60] - 297.0).abs() < 3.0, "rpm {}", rpm[60]);
    assert!(rpm.iter().all(|&r| (49.7..351.2).contains(&r)));
}

#[test]
fn a_steady_revolution_sees_a_closed_box() {
    let (revs, _) = decode_capture();
    let scan = revs[60].to_scan(0.0);
    assert_eq!(scan.len(), 360);
    let valid = scan.valid_count();
    assert!(valid > 300, "valid beams {valid}");
    // "Hand in box": every valid return is within a couple of metres.
    assert!(scan
        .beams()
        .iter()
        .filter(|b| b.valid)
        .all(|b| b.range_m < 3.0));
}

/// Old-firmware captures: a binary dump of 21 frames and one frame as hex text.
mod old_firmware {
    use super::common::{capture, decode};
    use plumbline_core::lidar::xv11_old::Xv11OldDecoder;

    #[test]
    fn sparkfun_dump_holds_21_frames() {
        let bytes = capture("sparkfun_noshield_dump_oldfw.bin");
        let (revs, stats) = decode::<Xv11OldDecoder>(&bytes);
        assert_eq!(revs.len(), 21);
        assert_eq!((stats.skipped_bytes, stats.malformed), (0, 0));
        // First reading of the first frame: bytes 21 80 AE 00, the invalid flag with code 0x21;
        // the second: AF 03 CD 00, 943 mm.
        let first = revs[0].reading(0).unwrap();
        assert!(first.invalid && first.distance_mm == 0x21);
        assert_eq!(
            revs[0].reading(1).map(|r| (r.distance_mm, r.strength)),
            Some((943, 0xCD))
        );
        let scan = revs[0].to_scan(0.0);
        assert_eq!(scan.len(), 360);
        assert_eq!(scan.valid_count(), 360 - 118);
    }

    #[test]
    fn one_run_hex_text_holds_one_frame() {
        let text = String::from_utf8(capture("OneRun_no_shield.txt")).unwrap();
        let bytes: Vec<u8> = text
            .trim_start_matches('\u{feff}')
            .split_whitespace()
            .map(|h| u8::from_str_radix(h, 16).unwrap())
            .collect();
        assert_eq!(bytes.len(), 1446);
        let (revs, stats) = decode::<Xv11OldDecoder>(&bytes);
        assert_eq!((revs.len(), stats.revolutions), (1, 1));
    }
}
