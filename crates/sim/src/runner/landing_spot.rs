//! Where a returning vehicle may come down: the home point, or the nearest point to it that
//! the walls in the latest scan leave room for.
//!
//! Home is kept in the map frame. When that frame has drifted (a long corridor the lidar cannot
//! measure along, then a small heading error carried over tens of metres), home can fall next
//! to a wall the vehicle sees, or inside it. Flown to directly, such a home takes the vehicle
//! into the wall, and a landing that holds it does too. The scan says where the walls are now,
//! whatever the map frame's error, so the spot is checked against the scan.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Scan;

/// Pushes away from the nearest wall before giving up: enough for a corridor or a corner.
const PUSHES: usize = 6;
/// A push goes this much past the clearance, so the next check does not fall just short of it
/// by rounding, m.
const PUSH_SLACK_M: f32 = 0.01;

/// The point nearest `home` that keeps `clearance_m` from the end of every valid beam of
/// `scan` (taken at `pose`, map frame), found by pushing away from the nearest end, and that
/// the vehicle reaches in a straight line keeping `radius_m` from every end (a home seen
/// behind a wall is not landed at from this side). `None` when no such point lies within
/// `max_shift_m` of home. A scan with no valid beam sees nothing to keep clear of, so home
/// stands.
pub fn landing_spot<const N: usize>(
    scan: &Scan<N>,
    pose: Pose2,
    home: Vec2,
    clearance_m: f32,
    radius_m: f32,
    max_shift_m: f32,
) -> Option<Vec2> {
    let ends = || {
        scan.beams()
            .iter()
            .filter(|b| b.valid)
            .map(move |b| pose.transform(b.point()))
    };
    let nearest = |p: Vec2| {
        ends()
            .map(|q| (q, (p - q).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    };
    let mut spot = home;
    for _ in 0..=PUSHES {
        let Some((wall, distance)) = nearest(spot) else {
            return Some(spot);
        };
        if distance >= clearance_m {
            let vehicle = pose.translation();
            let reachable = ends().all(|q| distance_to_segment(q, vehicle, spot) >= radius_m);
            return ((spot - home).norm() <= max_shift_m && reachable).then_some(spot);
        }
        // Away from the wall; a spot on the wall itself moves toward the vehicle, which the
        // field has kept clear.
        let away = if distance > f32::EPSILON {
            (spot - wall) * (1.0 / distance)
        } else {
            let to_vehicle = pose.translation() - wall;
            to_vehicle * (1.0 / to_vehicle.norm().max(f32::EPSILON))
        };
        spot = spot + away * (clearance_m - distance + PUSH_SLACK_M);
    }
    None
}

/// Distance from `p` to the segment from `a` to `b`.
fn distance_to_segment(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let length2 = ab.dot(ab);
    let t = if length2 > 0.0 {
        ((p - a).dot(ab) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_core::scan::Beam;

    /// A scan from `pose` of walls at `y = y_lo` and `y = y_hi` (map frame), one beam a degree.
    fn corridor(pose: Pose2, y_lo: f32, y_hi: f32) -> Scan<360> {
        let mut scan = Scan::new(0.0);
        for i in 0..360 {
            let bearing = (i as f32).to_radians();
            let world = pose.theta + bearing;
            let dy = world.sin();
            let range = if dy > 1e-3 {
                (y_hi - pose.y) / dy
            } else if dy < -1e-3 {
                (y_lo - pose.y) / dy
            } else {
                f32::INFINITY
            };
            let beam = if range <= 4.0 {
                Beam::new(bearing, range)
            } else {
                Beam {
                    valid: false,
                    ..Beam::new(bearing, 4.0)
                }
            };
            scan.push(beam).unwrap();
        }
        scan
    }

    #[test]
    fn a_home_clear_of_the_walls_stands() {
        let pose = Pose2::new(0.3, 0.1, 0.4);
        let scan = corridor(pose, -1.0, 1.0);
        let home = Vec2::new(0.0, 0.0);
        assert_eq!(landing_spot(&scan, pose, home, 0.5, 0.35, 0.5), Some(home));
    }

    #[test]
    fn a_home_against_a_wall_moves_out_to_the_clearance() {
        // The map frame has drifted: home is 0.25 m from the wall the vehicle sees.
        let pose = Pose2::new(0.2, -0.4, 2.4);
        let scan = corridor(pose, -1.25, 0.75);
        let home = Vec2::new(0.0, 0.5);
        let spot = landing_spot(&scan, pose, home, 0.5, 0.35, 0.5).expect("room in a 2 m corridor");
        let clearance = 0.75 - spot.y;
        assert!((0.5..0.53).contains(&clearance), "clearance {clearance}");
        assert!((spot - home).norm() < 0.3, "moved {:?}", spot - home);
    }

    #[test]
    fn no_spot_when_the_corridor_is_narrower_than_twice_the_clearance() {
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let scan = corridor(pose, -0.4, 0.4);
        assert_eq!(
            landing_spot(&scan, pose, Vec2::new(0.0, 0.0), 0.5, 0.35, 0.5),
            None
        );
    }

    #[test]
    fn no_spot_behind_a_wall_or_farther_than_the_shift_allowed() {
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let scan = corridor(pose, -1.0, 1.0);
        // Home 0.2 m behind the wall: pushed out, it is clear, but only through the wall.
        assert_eq!(
            landing_spot(&scan, pose, Vec2::new(0.0, 1.2), 0.5, 0.35, 0.5),
            None
        );
        // Far from the corridor's wall but more than the shift allowed from home.
        assert_eq!(
            landing_spot(&scan, pose, Vec2::new(0.0, 0.9), 0.5, 0.35, 0.3),
            None
        );
        assert!(landing_spot(&scan, pose, Vec2::new(0.0, 0.9), 0.5, 0.35, 0.5).is_some());
    }

    #[test]
    fn an_empty_scan_leaves_home_alone() {
        let scan: Scan<360> = Scan::new(0.0);
        let home = Vec2::new(1.0, 2.0);
        assert_eq!(
            landing_spot(&scan, Pose2::IDENTITY, home, 0.5, 0.35, 0.5),
            Some(home)
        );
    }
}
