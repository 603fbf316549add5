//! The CARMEN reader against hand-written lines with known contents, and against bad input.

use plumbline_io::carmen::{parse_log, write_robotlaser1, FovRule, ReadOptions};
use proptest::prelude::*;

fn parse(text: &str, opts: &ReadOptions) -> Result<plumbline_io::carmen::CarmenLog, String> {
    parse_log(text.as_bytes(), "test.clf", opts).map_err(|e| e.to_string())
}

const FLASER_3: &str = "FLASER 3 1.0 81.83 nan 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n";

#[test]
fn flaser_sentinels_and_nan_become_invalid_beams() {
    let log = parse(FLASER_3, &ReadOptions::default()).unwrap();
    let s = &log.scans[0];
    assert_eq!(s.valid, vec![true, false, false]);
    assert_eq!(s.timestamp_text, "100.25");
    assert_eq!(s.odom.unwrap().x_m, 0.5);
    // 3 beams, odd: both ends of 180 degrees, so 90 degrees apart.
    assert!((s.increment_rad.to_degrees() - 90.0).abs() < 1e-4);
}

#[test]
fn fov_override_changes_the_layout() {
    let opts = ReadOptions {
        fov: FovRule::Radians(std::f32::consts::PI / 2.0),
        ..Default::default()
    };
    let s = &parse(FLASER_3, &opts).unwrap().scans[0];
    assert!((s.start_angle_rad.to_degrees() + 45.0).abs() < 1e-4);
}

#[test]
fn other_records_params_and_comments_are_counted() {
    let text = format!("# comment\nPARAM robot_width 0.5 nohost 0\nNEFF 12.0 h 1\n{FLASER_3}ODOM 1 2 0.5 0 0 0 99.0 h 99.0\n\n");
    let log = parse(&text, &ReadOptions::default()).unwrap();
    let st = &log.stats;
    assert_eq!(
        (st.flaser, st.odom, st.params, st.other_records),
        (1, 1, 1, 1)
    );
    assert_eq!(st.comments, 2, "the comment and the blank line");
    assert_eq!(log.params[0], ("robot_width".into(), "0.5".into()));
    assert_eq!(log.odometry[0].pose.y_m, 2.0);
}

#[test]
fn truncated_line_names_file_line_and_field() {
    let text = format!("{FLASER_3}FLASER 3 1.0 2.0\n");
    let e = parse(&text, &ReadOptions::default()).unwrap_err();
    assert!(e.starts_with("test.clf:2: "), "{e}");
    assert!(e.contains("3 readings") && e.contains("truncated"), "{e}");
}

#[test]
fn a_beam_count_that_disagrees_with_the_line_is_an_error_naming_the_count() {
    // One reading more than the count says: read loosely, every later field shifts by one.
    let one_more = "FLASER 2 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n";
    let e = parse(one_more, &ReadOptions::default()).unwrap_err();
    assert!(e.starts_with("test.clf:1: FLASER: 2 readings"), "{e}");
    let one_less = "FLASER 4 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n";
    assert!(parse(one_less, &ReadOptions::default()).is_err());
}

#[test]
fn trailing_fields_are_an_error_for_every_record() {
    let extra = [
        format!("{} 7\n", FLASER_3.trim_end()),
        "ODOM 1 2 0.5 0 0 0 99.0 h 99.0 7\n".to_string(),
        format!("{} 7\n", ROBOTLASER1_4.trim_end()),
    ];
    for line in extra {
        let e = parse(&line, &ReadOptions::default()).unwrap_err();
        assert!(e.starts_with("test.clf:1: "), "{e}");
    }
}

#[test]
fn robotlaser1_remission_count_is_checked_against_the_line() {
    // Two remissions announced, three present.
    let line = ROBOTLASER1_4.replace(" 2 0.1 0.2 ", " 2 0.1 0.2 0.3 ");
    let e = parse(&line, &ReadOptions::default()).unwrap_err();
    assert!(e.contains("4 readings and 2 remissions"), "{e}");
    // A reading count one short makes the last reading pose as the remission count.
    let line = ROBOTLASER1_4.replace(" 0 4 1.0 5.6 2.5 0.0 2 ", " 0 3 1.0 5.6 2.5 0.0 2 ");
    assert!(parse(&line, &ReadOptions::default()).is_err());
}

#[test]
fn skip_bad_lines_counts_and_keeps_the_good_ones() {
    let text = format!("{FLASER_3}FLASER x\n{FLASER_3}ODOM 1 2 nan 0 0 0 1 h 1\n");
    let opts = ReadOptions {
        skip_bad_lines: true,
        ..Default::default()
    };
    let log = parse(&text, &opts).unwrap();
    assert_eq!(log.scans.len(), 2);
    assert_eq!(log.stats.bad_lines, 2);
    assert!(log
        .stats
        .first_bad_line
        .as_deref()
        .unwrap()
        .starts_with("test.clf:2:"));
}

#[test]
fn non_monotonic_scans_are_kept_in_file_order_and_counted() {
    let a = FLASER_3.replace("100.25", "200.0");
    let text = format!("{a}{FLASER_3}{a}");
    let log = parse(&text, &ReadOptions::default()).unwrap();
    let stamps: Vec<f64> = log.scans.iter().map(|s| s.timestamp_s).collect();
    assert_eq!(stamps, vec![200.0, 100.25, 200.0]);
    assert_eq!(log.stats.non_monotonic_scans, 1);
}

#[test]
fn absurd_beam_count_is_an_error_not_an_allocation() {
    let e = parse("FLASER 99999999999 1 2 3\n", &ReadOptions::default()).unwrap_err();
    assert!(e.contains("larger than"), "{e}");
}

const ROBOTLASER1_4: &str =
    "ROBOTLASER1 0 -2.094395 4.188790 0.006136 5.600 0.010 0 4 1.0 5.6 2.5 0.0 2 0.1 0.2 \
                0 0 0 1.5 2.5 0.3 0 0 0 0 0 1134864629.903219 host 0.5\n";

#[test]
fn robotlaser1_round_trips_through_the_writer() {
    let log = parse(ROBOTLASER1_4, &ReadOptions::default()).unwrap();
    let s = &log.scans[0];
    assert_eq!(
        s.valid,
        vec![true, false, true, false],
        "max range and zero are misses"
    );
    assert_eq!(s.odom.unwrap().theta_rad, 0.3);
    let mut out = Vec::new();
    write_robotlaser1(&mut out, s, "host").unwrap();
    let again = parse(std::str::from_utf8(&out).unwrap(), &ReadOptions::default()).unwrap();
    let t = &again.scans[0];
    assert_eq!(t.valid, s.valid);
    assert_eq!(t.timestamp_text, "1134864629.903219");
    assert!((t.start_angle_rad - s.start_angle_rad).abs() < 1e-6);
    assert!((t.increment_rad - s.increment_rad).abs() < 1e-6);
    assert!((t.ranges_m[0] - 1.0).abs() < 1e-6 && (t.ranges_m[2] - 2.5).abs() < 1e-6);
}

proptest! {
    /// Any bytes: the reader returns a log or an error, never panics.
    #[test]
    fn arbitrary_text_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse_log(&bytes[..], "fuzz", &ReadOptions::default());
    }

    /// Lines made of record names and numbers reach deep into the field parsers.
    #[test]
    fn plausible_records_never_panic(kind in prop::sample::select(vec!["FLASER", "ROBOTLASER1", "ODOM", "PARAM"]),
                                     nums in proptest::collection::vec(-5.0f64..400.0, 0..40)) {
        let mut line = kind.to_string();
        for n in nums { line.push_str(&format!(" {n}")); }
        let _ = parse(&line, &ReadOptions::default());
    }

    /// A well-formed FLASER record parses exactly, and the same record with its beam count off by
    /// any amount is refused: no shifted fields, whatever the readings are.
    #[test]
    fn flaser_parses_exactly_or_not_at_all(ranges in proptest::collection::vec(0.0f32..90.0, 1..30),
                                            off in -3i64..=3) {
        let body: Vec<String> = ranges.iter().map(|r| format!("{r}")).collect();
        let line = |n: i64| format!("FLASER {n} {} 1 2 0.5 1 2 0.5 42.125 host 43.5\n", body.join(" "));
        let log = parse(&line(ranges.len() as i64), &ReadOptions::default()).unwrap();
        prop_assert_eq!(&log.scans[0].timestamp_text, "42.125");
        prop_assert_eq!(log.scans[0].ranges_m.len(), ranges.len());
        let n = ranges.len() as i64 + off;
        if off != 0 && n >= 0 {
            prop_assert!(parse(&line(n), &ReadOptions::default()).is_err());
        }
    }
}
