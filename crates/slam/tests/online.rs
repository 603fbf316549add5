//! The online API on scans of a known room: every pose close to the truth, and the back end on
//! its worker thread reaching exactly the map the inline back end reaches.

mod common;

use common::room_scan;
use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_slam::{local_map_cells, Slam, SlamConfig};

/// Two laps of a 3 m circle in an 8 m x 6 m room, 5 cm and about 2.4 degrees a scan.
fn truth(k: usize) -> Pose2 {
    let a = k as f32 * 0.04;
    Pose2::new(
        4.0 + 1.5 * a.cos(),
        3.0 + 1.5 * a.sin(),
        a + core::f32::consts::FRAC_PI_2,
    )
}

fn run(threaded: bool) -> (Vec<Pose2>, Vec<Pose2>) {
    let config = SlamConfig::default();
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<360> = Slam::new(config, &mut cells, threaded).unwrap();
    let mut anchors = Vec::new();
    for k in 0..320 {
        let mut scan: Scan<360> = Scan::new(k as f64 * 0.2);
        for b in room_scan(truth(k), 8.0, 6.0, 360) {
            scan.push(b).unwrap();
        }
        let out = slam.add_scan(&scan, None);
        anchors.push((out.keyframe.unwrap(), out.relative));
    }
    let finished = slam.finish().unwrap();
    let poses = finished.backend.poses().to_vec();
    let scans = anchors.iter().map(|&(k, r)| poses[k].compose(r)).collect();
    (poses, scans)
}

#[test]
fn the_worker_thread_reaches_the_same_map_as_the_inline_back_end() {
    let (inline, _) = run(false);
    let (threaded, _) = run(true);
    assert_eq!(inline, threaded);
}

#[test]
fn every_scan_lands_near_its_true_pose_relative_to_the_first() {
    let (_, scans) = run(false);
    let start = truth(0);
    for (k, estimate) in scans.iter().enumerate() {
        let expected = start.between(truth(k));
        let (shift, turn) = estimate.distance_to(expected);
        assert!(
            shift < 0.05 && turn < 0.01,
            "scan {k}: {estimate:?} vs {expected:?}"
        );
    }
}
