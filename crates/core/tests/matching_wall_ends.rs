//! A corridor's axis, seen by a 4 m lidar: with doors in its walls the ends of the walls pin
//! the motion along it (finite variance, not degenerate); without, nothing does (degenerate,
//! unobserved). The scans are ray-cast from known poses, so the answer is exact.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::matching::{MatchConfig, MatchResult, ScanMatcher, UNOBSERVED_VARIANCE};
use synthetic::{corridor, scan_within, Seg};

#[allow(dead_code)] // each test binary uses its own share of the shared scenes
mod synthetic;

const RANGE_M: f32 = 4.0;
const NOISE_M: f32 = 0.01;

/// A 2 m corridor (y = -1 to 1) with a 1.2 m door in both walls every 6 m, and nothing behind
/// the doors within the lidar's reach.
fn corridor_with_doors() -> Vec<Seg> {
    let mut walls = Vec::new();
    for k in -8..8 {
        let (start, end) = (k as f32 * 6.0 + 3.6, k as f32 * 6.0 + 8.4);
        for y in [-1.0, 1.0] {
            walls.push((Vec2::new(start, y), Vec2::new(end, y)));
        }
    }
    walls
}

/// The match of the scan at `b` against the scan at `a`, from a guess 10 cm ahead of the truth
/// along the corridor.
fn match_along(world: &[Seg], a: Pose2, b: Pose2, seed: u64) -> (MatchResult, Pose2) {
    let tau = std::f32::consts::TAU;
    let mut m = ScanMatcher::<360>::new(MatchConfig::default());
    m.set_reference(&scan_within(world, a, 360, tau, NOISE_M, seed, RANGE_M))
        .unwrap();
    let truth = a.between(b);
    let guess = Pose2::new(truth.x + 0.1, truth.y, truth.theta);
    let current = scan_within(world, b, 360, tau, NOISE_M, seed + 1, RANGE_M);
    (m.match_scan(&current, guess).unwrap(), truth)
}

#[test]
fn door_frames_pin_the_corridor_axis_with_a_finite_variance() {
    // Several places along the corridor, 25 cm a scan, beside and between doors.
    for (i, x) in [2.0f32, 3.0, 4.2, 5.5].into_iter().enumerate() {
        let a = Pose2::new(x, 0.1, 0.0);
        let b = Pose2::new(x + 0.25, 0.0, 0.03);
        let (r, truth) = match_along(&corridor_with_doors(), a, b, 10 * i as u64);
        assert_eq!(r.quality.degenerate_direction, None, "x {x}: {r:?}");
        let var_x = r.covariance[0][0];
        // Not nil, not unobserved: a few centimetres at most, from beam spacings of 2-10 cm.
        assert!(var_x > 1e-6 && var_x < 4e-3, "x {x}: variance {var_x}");
        assert_eq!(r.observed_covariance, r.covariance);
        let error = (r.motion.x - truth.x).abs();
        assert!(error < 0.03, "x {x}: along-axis error {error} ({r:?})");
        assert!(
            error < 4.0 * var_x.sqrt(),
            "x {x}: {error} against sigma {}",
            var_x.sqrt()
        );
        assert!((r.motion.y - truth.y).abs() < 0.02, "x {x}: {:?}", r.motion);
    }
}

#[test]
fn a_featureless_corridor_stays_degenerate_where_its_walls_leave_the_lidars_reach() {
    let a = Pose2::new(0.0, 0.1, 0.0);
    let b = Pose2::new(0.25, 0.0, 0.03);
    let (r, truth) = match_along(&corridor(), a, b, 7);
    let v = r
        .quality
        .degenerate_direction
        .expect("a corridor without features must be degenerate");
    assert!(v.x.abs() > 0.99, "{v:?}");
    assert!(r.covariance[0][0] >= 0.9 * UNOBSERVED_VARIANCE, "{r:?}");
    // Across the axis the walls still decide.
    assert!((r.motion.y - truth.y).abs() < 0.02, "{:?}", r.motion);
}

/// A 2 m corridor along x that opens at x = 2 into a 2 m cross corridor and goes on beyond
/// x = 4: within a 4 m reach only the two corners where the side walls stop are in view.
fn corridor_into_a_crossing() -> Vec<Seg> {
    let mut walls = Vec::new();
    for y in [-1.0f32, 1.0] {
        let far = 10.0 * y;
        walls.push((Vec2::new(-50.0, y), Vec2::new(2.0, y)));
        walls.push((Vec2::new(2.0, y), Vec2::new(2.0, far)));
        walls.push((Vec2::new(4.0, y), Vec2::new(4.0, far)));
        walls.push((Vec2::new(4.0, y), Vec2::new(50.0, y)));
    }
    walls
}

#[test]
fn the_two_corners_of_a_crossing_ahead_pin_the_corridor_axis() {
    for (i, x) in [-0.2f32, 0.0, 0.3].into_iter().enumerate() {
        let a = Pose2::new(x, 0.1, 0.0);
        let b = Pose2::new(x + 0.25, 0.0, 0.03);
        let (r, truth) = match_along(&corridor_into_a_crossing(), a, b, 60 + 10 * i as u64);
        assert_eq!(r.quality.degenerate_direction, None, "x {x}: {r:?}");
        // Two ends give a few centimetres, and the variance says so.
        let (error, var_x) = ((r.motion.x - truth.x).abs(), r.covariance[0][0]);
        assert!(var_x > 1e-6 && var_x < 4e-3, "x {x}: variance {var_x}");
        assert!(error < 0.06, "x {x}: along-axis error {error} ({r:?})");
        assert!(
            error < 3.0 * var_x.sqrt(),
            "x {x}: {error} against sigma {}",
            var_x.sqrt()
        );
    }
}
