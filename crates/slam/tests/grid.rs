//! The occupancy grid on scans of known rooms: states, bounds, refusals, rebuilds.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Beam;
mod common;

use common::room_scan;
use plumbline_slam::grid::{CellState, GridConfig, GridError, OccupancyGrid, PreparedScan, Raster};

fn grid() -> OccupancyGrid {
    OccupancyGrid::new(GridConfig::default()).unwrap()
}

#[test]
fn a_room_maps_walls_occupied_inside_free_and_outside_unknown() {
    let mut g = grid();
    for (k, pose) in [(1.0, 1.0, 0.3), (3.0, 2.0, -1.0), (2.0, 2.5, 2.0)]
        .into_iter()
        .enumerate()
    {
        let pose = Pose2::new(pose.0, pose.1, pose.2);
        g.insert_scan(pose, &room_scan(pose, 4.0, 3.0, 720), 10.0)
            .unwrap_or_else(|e| panic!("scan {k}: {e}"));
    }
    assert_eq!(g.scans(), 3);
    // Every wall cell along the four walls (away from the corners) is occupied; the walls are
    // hit on the cell the exact range ends in, which is the cell past the boundary for the far
    // walls (x = 4, y = 3 fall on cell borders) and the cell before it for the near ones.
    let occupied: Vec<Vec2> = g.occupied_cells().map(|c| g.frame().center(c)).collect();
    assert!(occupied.len() > 200, "{} occupied cells", occupied.len());
    for p in &occupied {
        let to_wall =
            p.x.abs()
                .min((p.x - 4.0).abs())
                .min(p.y.abs())
                .min((p.y - 3.0).abs());
        assert!(
            to_wall <= 0.05,
            "occupied cell at {p:?} is {to_wall} m from a wall"
        );
    }
    for x in [0.5f32, 1.3, 2.2, 3.4] {
        for y in [0.4f32, 1.1, 2.6] {
            assert_eq!(g.state_at(Vec2::new(x, y)), CellState::Free, "({x}, {y})");
        }
    }
    assert_eq!(g.state_at(Vec2::new(-0.5, 1.0)), CellState::Unknown);
    assert_eq!(g.state_at(Vec2::new(5.0, 5.0)), CellState::Unknown);
    let b = g.bounds().unwrap();
    assert!(
        b.min.i >= -1 && b.max.i <= 80 && b.min.j >= -1 && b.max.j <= 60,
        "{b:?}"
    );
}

#[test]
fn rebuilding_in_any_order_gives_the_same_map() {
    let poses = [
        (1.0, 1.0, 0.3),
        (3.0, 2.0, -1.0),
        (2.0, 2.5, 2.0),
        (0.5, 2.5, 3.0),
    ]
    .map(|(x, y, t)| Pose2::new(x, y, t));
    let scans: Vec<PreparedScan> = poses
        .iter()
        .map(|&p| PreparedScan::from_beams(&room_scan(p, 4.0, 3.0, 360), 10.0, None).unwrap())
        .collect();
    let mut forward = grid();
    forward.rebuild(poses.iter().copied().zip(&scans)).unwrap();
    let mut backward = grid();
    backward
        .rebuild(poses.iter().copied().zip(&scans).rev())
        .unwrap();
    let (a, b) = (
        Raster::from_grid(&forward).unwrap(),
        Raster::from_grid(&backward).unwrap(),
    );
    assert_eq!(a, b);
    // A rebuild forgets what was there before: the same keyframes moved by 1 m give a map
    // moved by 20 cells.
    let moved: Vec<Pose2> = poses
        .iter()
        .map(|p| Pose2::new(p.x + 1.0, p.y, p.theta))
        .collect();
    backward.rebuild(moved.iter().copied().zip(&scans)).unwrap();
    let (fa, fb) = (forward.bounds().unwrap(), backward.bounds().unwrap());
    assert_eq!((fb.min.i - fa.min.i, fb.max.i - fa.max.i), (20, 20));
    assert_eq!(fb.min.j, fa.min.j);
}

#[test]
fn no_return_beams_clear_only_when_configured() {
    let beams: Vec<Beam> = (0..90).map(|k| Beam::invalid(k as f32 * 0.01)).collect();
    let mut g = grid();
    g.insert_scan(Pose2::default(), &beams, 4.0).unwrap();
    assert_eq!(g.state_at(Vec2::new(1.0, 0.2)), CellState::Unknown);
    let mut g = OccupancyGrid::new(GridConfig {
        no_return_clear_m: Some(2.0),
        ..GridConfig::default()
    })
    .unwrap();
    g.insert_scan(Pose2::default(), &beams, 4.0).unwrap();
    assert_eq!(g.state_at(Vec2::new(1.0, 0.2)), CellState::Free);
    assert_eq!(g.state_at(Vec2::new(2.5, 0.2)), CellState::Unknown);
    assert_eq!(g.occupied_cells().count(), 0);
}

#[test]
fn scans_beyond_the_bounds_are_refused_whole_and_change_nothing() {
    let mut g = OccupancyGrid::new(GridConfig {
        max_extent_m: 40.0,
        max_cells: 64 * 64 * 6,
        ..GridConfig::default()
    })
    .unwrap();
    let home = Pose2::new(1.0, 1.0, 0.0);
    g.insert_scan(home, &room_scan(home, 4.0, 3.0, 360), 10.0)
        .unwrap();
    let before = Raster::from_grid(&g).unwrap();
    let far = Pose2::new(50.0, 1.0, 0.0);
    let e = g
        .insert_scan(far, &room_scan(Pose2::default(), 4.0, 3.0, 360), 10.0)
        .unwrap_err();
    assert!(matches!(e, GridError::TooWide { .. }), "{e}");
    assert!(e.to_string().contains("maximum extent of 40 m"), "{e}");
    let wide = Pose2::new(25.0, 1.0, 0.0);
    let e = g
        .insert_scan(
            wide,
            &room_scan(Pose2::new(1.0, 1.0, 0.0), 12.0, 3.0, 360),
            15.0,
        )
        .unwrap_err();
    assert!(matches!(e, GridError::TooManyCells { .. }), "{e}");
    let e = g
        .insert_scan(Pose2::new(f32::NAN, 0.0, 0.0), &[], 10.0)
        .unwrap_err();
    assert_eq!(e, GridError::NonFinitePose);
    let e = g
        .insert_scan(home, &[Beam::new(0.0, 1e30)], f32::INFINITY)
        .unwrap_err();
    assert!(matches!(e, GridError::Config(_)), "{e}");
    assert_eq!(Raster::from_grid(&g).unwrap(), before);
    assert_eq!(g.scans(), 1);
    let mut huge = PreparedScan::new();
    huge.push_hit(Vec2::new(1e30, 0.0));
    assert!(matches!(
        g.insert(home, &huge),
        Err(GridError::TooWide { .. })
    ));
}

#[test]
fn memory_follows_the_area_mapped_not_its_bounding_box() {
    // An L of two 2 m wide, 60 m long corridors: about 240 m² inside a 3,600 m² bounding box.
    let mut g = grid();
    let mut scan = PreparedScan::new();
    for k in 0..=600 {
        let s = k as f32 * 0.1;
        scan.push_hit(Vec2::new(s, 1.0));
        scan.push_hit(Vec2::new(1.0, s));
    }
    for k in 0..=60 {
        let along = k as f32;
        g.insert(Pose2::new(along, 0.0, 0.0), &shift(&scan, -along, 0.0))
            .unwrap();
        g.insert(Pose2::new(0.0, along, 0.0), &shift(&scan, 0.0, -along))
            .unwrap();
    }
    let b = g.bounds().unwrap();
    let bbox_cells = (b.width() * b.height()) as usize;
    assert!(bbox_cells > 1_400_000, "{bbox_cells}");
    assert!(
        g.allocated_cells() * 8 < bbox_cells,
        "{} cells allocated for a {bbox_cells}-cell box",
        g.allocated_cells()
    );
    assert!(g.memory_bytes() < 2 << 20, "{} bytes", g.memory_bytes());
}

/// The points of `scan` seen from a sensor moved by (dx, dy): so all sensors see the same L.
fn shift(scan: &PreparedScan, dx: f32, dy: f32) -> PreparedScan {
    let mut out = PreparedScan::new();
    for p in scan.hits() {
        // Only the part of the L within 8 m of the sensor, as a short-range lidar would see it.
        let q = Vec2::new(p.x + dx, p.y + dy);
        if q.norm() < 8.0 {
            out.push_hit(q);
        }
    }
    out
}

#[test]
fn bad_configurations_name_the_field() {
    for (c, field) in [
        (
            GridConfig {
                resolution_m: 0.0,
                ..GridConfig::default()
            },
            "resolution_m",
        ),
        (
            GridConfig {
                max_extent_m: 1e9,
                ..GridConfig::default()
            },
            "max_extent_m",
        ),
        (
            GridConfig {
                max_cells: 0,
                ..GridConfig::default()
            },
            "max_cells",
        ),
        (
            GridConfig {
                free_ratio: 0.7,
                ..GridConfig::default()
            },
            "free_ratio",
        ),
        (
            GridConfig {
                no_return_clear_m: Some(f32::NAN),
                ..GridConfig::default()
            },
            "no_return_clear_m",
        ),
    ] {
        let e = OccupancyGrid::new(c).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
}

#[test]
fn a_few_hits_just_beyond_a_well_hit_wall_are_not_a_second_wall() {
    // Forty beams end in the wall cell at x = 2.02 m, three overshoot into the next cell
    // (no beam ever passes through it, so its hit ratio is 1); a post 1 m away is hit twice.
    let mut scan = PreparedScan::new();
    for _ in 0..40 {
        scan.push_hit(Vec2::new(2.02, 0.01));
    }
    for _ in 0..3 {
        scan.push_hit(Vec2::new(2.07, 0.01));
    }
    for _ in 0..2 {
        scan.push_hit(Vec2::new(1.02, 1.01));
    }
    for fraction in [0.25, 0.0] {
        let mut g = OccupancyGrid::new(GridConfig {
            neighbour_hit_fraction: fraction,
            ..GridConfig::default()
        })
        .unwrap();
        g.insert(Pose2::default(), &scan).unwrap();
        assert_eq!(g.state_at(Vec2::new(2.02, 0.01)), CellState::Occupied);
        assert_eq!(g.state_at(Vec2::new(1.02, 1.01)), CellState::Occupied);
        let beyond = if fraction > 0.0 {
            CellState::Unknown
        } else {
            CellState::Occupied
        };
        assert_eq!(g.state_at(Vec2::new(2.07, 0.01)), beyond, "{fraction}");
    }
}
