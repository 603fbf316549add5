//! What a scan's match reports it observed, against the geometry it saw: in a corridor of two
//! parallel walls nothing pins the motion along the walls and everything pins it across them;
//! in a room both directions are pinned. The vehicle is turned against the corridor, so the
//! direction must come out in the map frame's axes, not the scan's.

mod common;

use common::room_scan;
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::{Beam, Scan};
use plumbline_slam::{local_map_cells, ScanPose, Slam, SlamConfig};

/// The lidar's reach, m: the corridor's ends stay out of sight.
const RANGE_M: f32 = 6.0;
const BEAMS: usize = 360;

/// Beams from `pose` to the walls y = 0 and y = `width` (endless along x), no return past
/// [`RANGE_M`].
fn corridor_scan(pose: Pose2, width: f32) -> Vec<Beam> {
    (0..BEAMS)
        .map(|k| {
            let a = k as f32 * core::f32::consts::TAU / BEAMS as f32 - core::f32::consts::PI;
            let dy = (pose.theta + a).sin();
            let t = if dy > 0.0 {
                (width - pose.y) / dy
            } else {
                -pose.y / dy
            };
            if t.is_finite() && t <= RANGE_M {
                Beam::new(a, t)
            } else {
                Beam::invalid(a)
            }
        })
        .collect()
}

/// Feeds the scans seen along `truth` and returns what the SLAM made of each.
fn fly(truth: &[Pose2], scan_at: impl Fn(Pose2) -> Vec<Beam>) -> Vec<ScanPose> {
    let config = SlamConfig::default();
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<BEAMS> = Slam::new(config, &mut cells, false).unwrap();
    truth
        .iter()
        .enumerate()
        .map(|(k, &pose)| {
            let mut scan: Scan<BEAMS> = Scan::new(k as f64 * 0.2);
            for b in scan_at(pose) {
                scan.push(b).unwrap();
            }
            slam.add_scan(&scan, None)
        })
        .collect()
}

#[test]
fn a_corridor_is_unobserved_along_its_walls_and_tight_across_them() {
    // 3 cm a scan along a 2 m corridor, the vehicle turned 0.5 rad against it.
    let heading = 0.5;
    let truth: Vec<Pose2> = (0..60)
        .map(|k| Pose2::new(k as f32 * 0.03, 0.8, heading))
        .collect();
    let scans = fly(&truth, |p| corridor_scan(p, 2.0));
    assert!(
        scans[0].observed.is_none(),
        "the first scan matches nothing"
    );
    // The map frame is the first scan's: the corridor runs at -heading in it.
    let along = Pose2::new(0.0, 0.0, -heading).rotate(Vec2::new(1.0, 0.0));
    let across = along.perp();
    let start = truth[0];
    for (k, s) in scans.iter().enumerate().skip(1) {
        let o = s
            .observed
            .unwrap_or_else(|| panic!("scan {k} was not matched: {s:?}"));
        let d = o
            .degenerate_direction
            .unwrap_or_else(|| panic!("scan {k}: no degenerate direction: {o:?}"));
        assert!(d.dot(along).abs() > 0.999, "scan {k}: direction {d:?}");
        // Information along the walls: at most 0.01 per m² (a sigma of 10 m); across: a
        // centimetre's sigma or better.
        assert!(o.variance_along(along) >= 100.0, "scan {k}: {o:?}");
        assert!(o.variance_along(across) < 1e-4, "scan {k}: {o:?}");
        assert!(o.covariance[2][2] < 1e-4, "scan {k}: heading {o:?}");
        // What was observed is right: the distance to the walls and the heading.
        let expected = start.between(truth[k]);
        let off = s.pose.translation() - expected.translation();
        assert!(off.dot(across).abs() < 0.01, "scan {k}: {s:?}");
        assert!((s.pose.theta - expected.theta).abs() < 0.005, "scan {k}");
    }
}

#[test]
fn a_room_is_observed_tightly_in_every_direction() {
    let truth: Vec<Pose2> = (0..60)
        .map(|k| Pose2::new(2.0 + k as f32 * 0.03, 2.5 + k as f32 * 0.01, 0.5))
        .collect();
    let scans = fly(&truth, |p| room_scan(p, 8.0, 6.0, BEAMS));
    assert!(scans[0].observed.is_none());
    for (k, s) in scans.iter().enumerate().skip(1) {
        let o = s
            .observed
            .unwrap_or_else(|| panic!("scan {k} was not matched: {s:?}"));
        assert_eq!(o.degenerate_direction, None, "scan {k}: {o:?}");
        for angle in [0.0f32, 0.4, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8] {
            let u = Vec2::new(angle.cos(), angle.sin());
            assert!(o.variance_along(u) < 1e-4, "scan {k} along {angle}: {o:?}");
        }
        assert!(o.covariance[2][2] < 1e-4, "scan {k}: heading {o:?}");
    }
}
