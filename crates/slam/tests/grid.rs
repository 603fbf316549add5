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

/// A 1° scan from `pose` of a wall at x = 3.025 and, when `leg` is given, a post of radius
/// 5 cm at that point (a person's leg): (angle, range) of every beam that hits either.
fn wall_and_leg_scan(pose: Pose2, leg: Option<Vec2>) -> Vec<Beam> {
    let (wall_x, radius) = (3.025f32, 0.05f32);
    (-50..=50)
        .filter_map(|k| {
            let angle = (k as f32).to_radians();
            let (s, c) = (pose.theta + angle).sin_cos();
            let to_wall = (c > 0.0).then(|| (wall_x - pose.x) / c);
            let to_leg = leg.and_then(|l| {
                // The nearer root of |pose + t (c, s) - l| = radius, if the ray meets the post.
                let (dx, dy) = (pose.x - l.x, pose.y - l.y);
                let b = dx * c + dy * s;
                let disc = b * b - (dx * dx + dy * dy - radius * radius);
                (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|&t| t > 0.0)
            });
            let range = match (to_wall, to_leg) {
                (Some(w), Some(l)) => w.min(l),
                (w, l) => w.or(l)?,
            };
            Some(Beam::new(angle, range))
        })
        .collect()
}

#[test]
fn scans_that_see_through_a_passer_by_clear_it_and_leave_the_wall() {
    let leg = Vec2::new(1.5, 0.02);
    let caught = Pose2::new(0.0, 0.0, 0.0);
    // Keyframes: one catches the leg in front of the wall; two closer ones see only the wall
    // (from x = 2 they cannot look back at the leg), so each wall cell ahead has several hits.
    let build = |times_caught: usize| {
        let mut g = grid();
        for _ in 0..times_caught {
            g.insert_scan(caught, &wall_and_leg_scan(caught, Some(leg)), 10.0)
                .unwrap();
        }
        for y in [0.0, 0.01] {
            let pose = Pose2::new(2.0, y, 0.0);
            g.insert_scan(pose, &wall_and_leg_scan(pose, None), 10.0)
                .unwrap();
        }
        g
    };
    let leg_cells = |g: &OccupancyGrid| -> Vec<(f32, f32)> {
        g.occupied_cells()
            .map(|c| g.frame().center(c))
            .filter(|p| (*p - leg).norm() < 0.15)
            .map(|p| (p.x, p.y))
            .collect()
    };
    // The later scans, from beside where the leg was caught, after the person walked on.
    let later: Vec<(Pose2, PreparedScan)> = (1..=6)
        .map(|k| {
            let pose = Pose2::new(0.0, 0.03 * k as f32 - 0.1, 0.0);
            let scan = PreparedScan::from_beams(&wall_and_leg_scan(pose, None), 10.0, None);
            (pose, scan.unwrap())
        })
        .collect();
    let wall_cells = |g: &OccupancyGrid| -> usize {
        (-8..=8)
            .filter(|&k| g.state_at(Vec2::new(3.03, 0.05 * k as f32)) == CellState::Occupied)
            .count()
    };

    let mut g = build(1);
    assert!(
        !leg_cells(&g).is_empty(),
        "the keyframes alone keep the leg"
    );
    assert_eq!(wall_cells(&g), 17);
    let bounds = g.bounds();
    g.see_through(later.iter().map(|(pose, scan)| (*pose, scan)), 2)
        .unwrap();
    assert_eq!(leg_cells(&g), vec![], "seen through, the leg is gone");
    assert_ne!(g.state_at(leg), CellState::Occupied);
    assert_eq!(wall_cells(&g), 17, "the wall behind it stays");
    assert_eq!(g.bounds(), bounds, "seeing through adds no area");

    // An object three keyframes caught is not something passing by: it stays.
    let mut g = build(3);
    let before = leg_cells(&g);
    g.see_through(later.iter().map(|(pose, scan)| (*pose, scan)), 2)
        .unwrap();
    assert!(!before.is_empty());
    assert_eq!(leg_cells(&g), before);
    assert_eq!(
        g.see_through([(Pose2::new(f32::NAN, 0.0, 0.0), &later[0].1)], 2),
        Err(GridError::NonFinitePose)
    );
}

/// A beam from `from` at angle `a` in a world of a wall (zero thickness) along y = 0 from
/// x = 0 to x = 2, and a far wall at y = -3: the lidar returns nothing from the first wall
/// when it meets it at less than 11.5° (the XV-11's grazing limit).
fn jamb_beam(from: Vec2, a: f32) -> Beam {
    let (dx, dy) = (a.cos(), a.sin());
    if dy.abs() > 1e-6 {
        let t = -from.y / dy;
        let x = from.x + t * dx;
        if t > 0.0 && (0.0..=2.0).contains(&x) {
            return if dy.abs() < 0.2 {
                Beam::invalid(a)
            } else {
                Beam::new(a, t)
            };
        }
        let t = (-3.0 - from.y) / dy;
        if t > 0.0 {
            return Beam::new(a, t);
        }
    }
    Beam::invalid(a)
}

fn jamb_scan(at: Vec2) -> PreparedScan {
    let beams: Vec<Beam> = (0..360)
        .map(|k| jamb_beam(at, (k as f32).to_radians()))
        .collect();
    PreparedScan::from_beams(&beams, 10.0, None).unwrap()
}

#[test]
fn a_wall_end_seen_edge_on_by_grazing_beams_stays_occupied() {
    // A few keyframes face the wall; many more fly along its line, 0.2 m to 0.4 m off it, so
    // that beams passing its end at a few degrees run along its last cells.
    let facing: Vec<(Pose2, PreparedScan)> = (0..6)
        .map(|k| {
            let at = Vec2::new(0.4 + 0.3 * k as f32, 1.5);
            (Pose2::new(at.x, at.y, 0.0), jamb_scan(at))
        })
        .collect();
    let along: Vec<(Pose2, PreparedScan)> = (0..20)
        .map(|k| {
            let at = Vec2::new(-3.0 + 0.1 * k as f32, 0.2 + 0.01 * k as f32);
            (Pose2::new(at.x, at.y, 0.0), jamb_scan(at))
        })
        .collect();
    let end_cells = |g: &OccupancyGrid| {
        (0..10)
            .filter(|&k| {
                g.state_at(Vec2::new(1.975 - 0.05 * k as f32, 0.01)) == CellState::Occupied
            })
            .count()
    };
    let build = |config: GridConfig| {
        let mut g = OccupancyGrid::new(config).unwrap();
        for (pose, scan) in facing.iter().chain(&along) {
            g.insert(*pose, scan).unwrap();
        }
        let mut rebuilt = OccupancyGrid::new(config).unwrap();
        rebuilt
            .rebuild(along.iter().chain(&facing).map(|(p, s)| (*p, s)))
            .unwrap();
        (g, rebuilt)
    };
    let (one_by_one, rebuilt) = build(GridConfig::default());
    assert_eq!(end_cells(&one_by_one), 10, "inserted one by one");
    assert_eq!(
        end_cells(&rebuilt),
        10,
        "rebuilt, the grazing keyframes first"
    );
    // The same beams clearing every cell they pass wear the end away.
    let (worn, _) = build(GridConfig {
        solid_hits: 0,
        ..GridConfig::default()
    });
    assert!(end_cells(&worn) < 5, "{} of 10 left", end_cells(&worn));
}

#[test]
fn a_person_seen_from_the_front_is_cleared_by_the_beams_that_cross_where_they_stood() {
    // A person 0.4 m across stands 2 m in front of the sensor for a few keyframes (their
    // front spread over two cells in depth by range noise), then walks away; the keyframes
    // after see the wall 4 m away through where they stood.
    let scan = |person: bool, k: usize| {
        let beams: Vec<Beam> = (-40..=40)
            .map(|b| {
                let a = (b as f32 * 0.5).to_radians();
                let wall = 4.0 / a.cos();
                let near = 2.0 / a.cos() + if (b + k as i32) % 2 == 0 { 0.0 } else { 0.05 };
                let r = if person && (2.0 * a.tan()).abs() < 0.2 {
                    near
                } else {
                    wall
                };
                Beam::new(a, r)
            })
            .collect();
        PreparedScan::from_beams(&beams, 10.0, None).unwrap()
    };
    let pose = Pose2::new(0.0, 0.0, 0.0);
    let mut g = grid();
    for k in 0..6 {
        g.insert(pose, &scan(true, k)).unwrap();
    }
    let stood = (0..8)
        .map(|k| Vec2::new(2.02, -0.175 + 0.05 * k as f32))
        .filter(|&p| g.state_at(p) == CellState::Occupied)
        .count();
    assert!(stood >= 6, "{stood} of 8 cells occupied while they stand");
    for k in 0..60 {
        g.insert(pose, &scan(false, k)).unwrap();
    }
    for k in 0..8 {
        let p = Vec2::new(2.02, -0.175 + 0.05 * k as f32);
        assert_eq!(g.state_at(p), CellState::Free, "{p:?}");
    }
}
