//! Frames that pass their checks but that the sensor cannot have sent are refused and counted.

use plumbline_core::lidar::scip::ScipDecoder;
use plumbline_core::lidar::ByteDecoder;

/// A SCIP 2.0 line: payload, then the low 6 bits of its byte sum plus 0x30.
fn scip_line(payload: &[u8]) -> Vec<u8> {
    let sum = payload.iter().map(|&b| u32::from(b)).sum::<u32>();
    let mut line = payload.to_vec();
    line.extend([(sum & 0x3F) as u8 + 0x30, b'\n']);
    line
}

/// A GD reply (three characters a value, 1000 mm each) for steps `start..=end`.
fn gd_reply(start: u16, end: u16) -> Vec<u8> {
    let mut out = format!("GD{start:04}{end:04}00\n").into_bytes();
    out.extend(scip_line(b"00"));
    out.extend(scip_line(b"0000"));
    let data: Vec<u8> = (start..=end).flat_map(|_| *b"0?X").collect();
    for chunk in data.chunks(64) {
        out.extend(scip_line(chunk));
    }
    out.push(b'\n');
    out
}

#[test]
fn an_urg_reply_for_steps_the_sensor_does_not_have_is_implausible() {
    // The URG-04LX has steps 0..=768: a well-formed reply for 760..=780 has impossible angles.
    let mut revs = Vec::new();
    let mut urg = ScipDecoder::<769>::new();
    urg.decode_into(&gd_reply(760, 780), &mut revs);
    assert!(revs.is_empty());
    assert_eq!((urg.stats().implausible, urg.stats().revolutions), (1, 0));
    // The same reply within the sensor decodes, and 1000 mm is what it says.
    let mut urg = ScipDecoder::<769>::new();
    urg.decode_into(&gd_reply(740, 760), &mut revs);
    assert_eq!((revs.len(), urg.stats().implausible), (1, 0));
    assert!(revs[0].ranges_mm().iter().all(|&r| r == 1000));
}
