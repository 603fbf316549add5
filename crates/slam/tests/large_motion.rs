//! Large motion between scans (a log with few scans, a sharp turn): the tracker finds the
//! motion by a wide search, and scans it cannot match are counted as lost, interval by interval.

mod common;

use common::room_scan;
use plumbline_core::geom::Pose2;
use plumbline_core::scan::{Beam, Scan};
use plumbline_slam::{local_map_cells, ScanPose, Slam, SlamConfig};

const W: f32 = 8.0;
const H: f32 = 6.0;

fn scan_at(pose: Pose2, stamp_s: f64) -> Scan<360> {
    let mut scan = Scan::new(stamp_s);
    for b in room_scan(pose, W, H, 360) {
        scan.push(b).unwrap();
    }
    scan
}

/// What a covered or spun-down lidar sends: too few returns to match.
fn blind_scan(stamp_s: f64) -> Scan<360> {
    let mut scan = Scan::new(stamp_s);
    for k in 0..360 {
        let a = (k as f32).to_radians() - core::f32::consts::PI;
        let beam = if k < 5 {
            Beam::new(a, 2.0)
        } else {
            Beam::invalid(a)
        };
        scan.push(beam).unwrap();
    }
    scan
}

/// Tracks a scan at `first`, then one at `second` a scan period later; the second's pose
/// relative to the first, and how many wide searches were used.
fn track_pair(config: SlamConfig, first: Pose2, second: Pose2) -> (Pose2, usize) {
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<360> = Slam::new(config, &mut cells, false).unwrap();
    slam.add_scan(&scan_at(first, 0.0), None);
    let out: ScanPose = slam.add_scan(&scan_at(second, 0.2), None);
    (out.pose, slam.tracking_stats().guess_searches_used)
}

#[test]
fn half_a_metre_and_150_degrees_between_two_scans_is_recovered() {
    let first = Pose2::new(2.5, 2.0, 0.3);
    let motion = Pose2::new(0.5 * 0.6f32.cos(), 0.5 * 0.6f32.sin(), 150f32.to_radians());
    let second = first.compose(motion);
    let (found, searches) = track_pair(SlamConfig::default(), first, second);
    let (shift, turn) = found.distance_to(motion);
    assert!(shift < 0.05 && turn < 0.02, "{found:?} vs {motion:?}");
    assert_eq!(
        searches, 1,
        "the repeated (zero) motion fits badly: one wide search"
    );
    // Without the guard the matcher starts from standing still, 150° off, and cannot get there.
    let mut config = SlamConfig::default();
    config.guard.enabled = false;
    let (unguarded, _) = track_pair(config, first, second);
    let (shift, turn) = unguarded.distance_to(motion);
    assert!(shift > 0.2 || turn > 0.2, "{unguarded:?}");
}

#[test]
fn every_lost_interval_is_counted_and_its_scans_predicted() {
    let config = SlamConfig::default();
    let mut cells = local_map_cells(&config);
    let mut slam: Slam<360> = Slam::new(config, &mut cells, false).unwrap();
    // Standing in the room; the lidar goes blind for three scans, sees again, goes blind for
    // two, sees again.
    let pose = Pose2::new(3.0, 2.5, 0.2);
    let pattern = [
        true, true, false, false, false, true, true, false, false, true,
    ];
    let mut predicted = Vec::new();
    for (k, &sees) in pattern.iter().enumerate() {
        let stamp = k as f64 * 0.2;
        let scan = if sees {
            scan_at(pose, stamp)
        } else {
            blind_scan(stamp)
        };
        predicted.push(slam.add_scan(&scan, None).predicted);
    }
    let blind: Vec<bool> = pattern.iter().map(|&sees| !sees).collect();
    assert_eq!(predicted, blind);
    let stats = slam.tracking_stats();
    assert_eq!(stats.predicted_scans, 5);
    assert_eq!(stats.lost_intervals, 2);
    assert_eq!(stats.scans, pattern.len());
}
