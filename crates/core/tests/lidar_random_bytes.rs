//! Every decoder on random and mangled bytes (the fuzzers' checks, run by every test run): no panic,
//! counters that add up, and real packets recovered from around garbage. Deterministic: proptest
//! runs with a fixed seed from `proptest-regressions`-free config below.

use plumbline_core::lidar::xv11_revolution::{Revolution, Xv11Decoder};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

mod common;
use common::{capture, decode};

/// A runner with a fixed seed so a failure reproduces bit for bit.
pub fn runner(cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]))
}

fn xv11(bytes: &[u8]) -> (Vec<Revolution>, plumbline_core::lidar::DecodeStats) {
    decode::<Xv11Decoder>(bytes)
}

#[test]
fn xv11_random_bytes_never_panic_and_counters_add_up() {
    runner(512)
        .run(&proptest::collection::vec(any::<u8>(), 0..4096), |bytes| {
            let (revs, s) = xv11(&bytes);
            prop_assert_eq!(s.bytes, bytes.len() as u64);
            prop_assert!(u64::from(s.packets_ok) * 22 + s.skipped_bytes <= s.bytes);
            let placed: u32 = revs.iter().map(Revolution::packets).sum();
            prop_assert_eq!(placed, s.packets_ok);
            Ok(())
        })
        .unwrap();
}

#[test]
fn xv11_garbage_between_real_packets_loses_none() {
    let capture = capture("hand_in_box.bin");
    // 200 packets of the in-order part, starting at the first A0 (offset found by the decoder
    // test in `xv11_capture.rs`: packet 58 is at byte 6, so A0 is 32 packets later).
    let clean = &capture[6 + 22 * 32..6 + 22 * 232];
    let (_, base) = xv11(clean);
    assert_eq!(base.packets_ok, 200);
    let (clean_revs, _) = xv11(clean);
    let beams = |r: &Revolution| r.to_scan(0.0).beams().to_vec();
    let garbage = proptest::collection::vec(
        any::<u8>().prop_filter("no start byte", |&b| b != 0xFA),
        0..40,
    );
    runner(256)
        .run(
            &proptest::collection::vec((0usize..200, garbage), 1..8),
            |inserts| {
                let mut bytes = Vec::with_capacity(clean.len() + 400);
                for (k, pkt) in clean.chunks(22).enumerate() {
                    for (_, g) in inserts.iter().filter(|(at, _)| *at == k) {
                        bytes.extend_from_slice(g);
                    }
                    bytes.extend_from_slice(pkt);
                }
                let (revs, s) = xv11(&bytes);
                prop_assert_eq!(s.packets_ok, 200);
                // Same beams; only the stream offsets moved.
                prop_assert!(revs.iter().map(beams).eq(clean_revs.iter().map(beams)));
                Ok(())
            },
        )
        .unwrap();
}

#[test]
fn xv11_truncation_anywhere_never_shifts_a_reading() {
    let capture = capture("hand_in_box.bin");
    let clean = &capture[6 + 22 * 32..6 + 22 * 122]; // exactly one revolution
    let (full, _) = xv11(clean);
    assert_eq!(full.len(), 1);
    runner(256)
        .run(&(0usize..clean.len(), 1usize..60), |(cut, len)| {
            let end = (cut + len).min(clean.len());
            let bytes = [&clean[..cut], &clean[end..]].concat();
            let (revs, _) = xv11(&bytes);
            for rev in &revs {
                for deg in 0..360 {
                    if let Some(r) = rev.reading(deg) {
                        prop_assert_eq!(Some(r), full[0].reading(deg));
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}

fn random_bytes() -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(any::<u8>(), 0..6000)
}

#[test]
fn xv11_old_random_bytes_never_panic() {
    use plumbline_core::lidar::xv11_old::{Xv11OldDecoder, FRAME_LEN};
    runner(256)
        .run(&random_bytes(), |bytes| {
            let mut d = Xv11OldDecoder::new();
            let n =
                bytes.iter().filter_map(|&b| d.push(b)).count() + usize::from(d.finish().is_some());
            prop_assert!(n <= bytes.len() / FRAME_LEN);
            prop_assert_eq!(d.stats().bytes, bytes.len() as u64);
            Ok(())
        })
        .unwrap();
}

#[test]
fn scip_random_bytes_and_random_lines_never_panic() {
    use plumbline_core::lidar::scip::ScipDecoder;
    // Raw bytes, and lines of SCIP-looking characters (which reach the deeper states).
    let scipish = proptest::collection::vec(
        prop_oneof![Just(b'\n'), 0x30u8..0x70, Just(b'M'), Just(b'D')],
        0..6000,
    );
    for strategy in [random_bytes().boxed(), scipish.boxed()] {
        runner(256)
            .run(&strategy, |bytes| {
                let mut d = ScipDecoder::<769>::new();
                for &b in &bytes {
                    if let Some(scan) = d.push(b) {
                        prop_assert!(!scan.ranges_mm().is_empty() && scan.cluster >= 1);
                    }
                }
                prop_assert_eq!(d.stats().bytes, bytes.len() as u64);
                Ok(())
            })
            .unwrap();
    }
}

#[test]
fn rplidar_random_bytes_never_panic_and_revolutions_are_plausible() {
    use plumbline_core::lidar::rplidar::RplidarDecoder;
    runner(256)
        .run(&random_bytes(), |bytes| {
            let mut d = RplidarDecoder::<800>::new();
            let mut nodes = 0u32;
            let mut revs: Vec<_> = bytes.iter().filter_map(|&b| d.push(b)).collect();
            revs.extend(d.finish());
            for r in &revs {
                nodes += r.nodes().len() as u32;
                prop_assert!(r.nodes().iter().all(|n| n.angle_q6 < 360 * 64));
                prop_assert!(r.is_plausible());
            }
            let s = d.stats();
            prop_assert_eq!(s.revolutions as usize, revs.len());
            // Nodes of implausible revolutions are dropped with them.
            if s.implausible == 0 {
                prop_assert_eq!(nodes + s.overflow, s.packets_ok);
            } else {
                prop_assert!(nodes + s.overflow < s.packets_ok);
            }
            prop_assert!(u64::from(s.packets_ok) * 5 + s.skipped_bytes <= s.bytes);
            Ok(())
        })
        .unwrap();
}

/// `feed` copies packet bodies in bulk; whatever the chunking, it must agree with `push`.
#[test]
fn xv11_feed_in_any_chunks_equals_push_byte_by_byte() {
    let capture = capture("hand_in_box.bin");
    let (want, want_stats) = xv11(&capture);
    let feed = |bytes: &[u8], chunk: usize| {
        let mut d = Xv11Decoder::new();
        let mut revs = Vec::new();
        for piece in bytes.chunks(chunk) {
            let mut rest = piece;
            while !rest.is_empty() {
                let (n, rev) = d.feed(rest);
                rest = &rest[n..];
                revs.extend(rev);
            }
        }
        revs.extend(d.finish());
        (revs, d.stats())
    };
    assert_eq!(feed(&capture, capture.len()), (want.clone(), want_stats));
    let garbage_mixed = (
        proptest::collection::vec(any::<u8>(), 0..3000),
        1usize..64,
        0usize..capture.len() - 3000,
    );
    runner(64)
        .run(&garbage_mixed, |(garbage, chunk, at)| {
            let bytes = [&capture[at..at + 3000], &garbage[..], &capture[..2000]].concat();
            prop_assert_eq!(feed(&bytes, chunk), xv11(&bytes));
            Ok(())
        })
        .unwrap();
}
