//! Exploration decisions on hand-drawn rooms with known answers: the frontier of a room with
//! a door is the door, a gap narrower than the vehicle is never planned through, a closed room
//! is done, and paths have the lengths geometry says they must.

mod common;

use common::{explorer, explorer_with, room, Wall};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_explore::frontier::clusters;
use plumbline_explore::plan_grid::PlanGrid;
use plumbline_explore::{DoneReason, ExploreConfig, ExploreStep};

fn at(x: f32, y: f32) -> Pose2 {
    Pose2::new(x, y, 0.0)
}

/// A 5 m x 4 m room with a door of `width` in the middle of its right wall, opening on a
/// 2.5 m wide corridor that runs 2 m past the room at each end (the lidar sees into it
/// through the door and no farther).
fn room_with_door(width: f32) -> Vec<Wall> {
    let mut walls = room(0.0, -2.0, 7.5, 6.0, &[]);
    walls.extend([
        [0.0, 0.0, 5.0, 0.0],
        [0.0, 4.0, 5.0, 4.0],
        [5.0, -2.0, 5.0, 2.0 - width / 2.0],
        [5.0, 2.0 + width / 2.0, 5.0, 6.0],
    ]);
    walls
}

const INSIDE: [Pose2; 3] = [
    Pose2 {
        x: 1.5,
        y: 2.0,
        theta: 0.0,
    },
    Pose2 {
        x: 3.5,
        y: 1.2,
        theta: 0.3,
    },
    Pose2 {
        x: 3.5,
        y: 2.8,
        theta: -0.2,
    },
];

#[test]
fn the_frontier_of_a_room_with_a_door_is_the_door() {
    let walls = room_with_door(1.2);
    let mut e = explorer(&walls, &INSIDE);
    let config = ExploreConfig::default();
    let g = PlanGrid::new(
        e.map().grid(),
        config.plan_factor(),
        config.clearance(),
        None,
    );
    let f = clusters(&g, 4);
    assert!(!f.clusters.is_empty());
    for c in &f.clusters {
        assert!(c.centroid.x > 5.0, "a frontier inside the room: {c:?}");
    }

    let ExploreStep::Waypoint(w) = e.next(at(1.5, 2.0)) else {
        panic!("a door to explore is not done");
    };
    let goal = e.goal().unwrap();
    assert!(goal.x > 5.0, "goal {goal:?} is not beyond the door");
    // The lookahead point is 1 m along the path, which leaves the room through the door.
    assert!(
        ((w - Vec2::new(1.5, 2.0)).norm() - 1.0).abs() < 0.05,
        "{w:?}"
    );
    let path = e.path().unwrap();
    let crossing = path
        .waypoints
        .windows(2)
        .find(|s| s[0].x <= 5.0 && s[1].x >= 5.0)
        .unwrap();
    let t = (5.0 - crossing[0].x) / (crossing[1].x - crossing[0].x);
    let y = crossing[0].y + t * (crossing[1].y - crossing[0].y);
    assert!((y - 2.0).abs() < 0.25, "leaves the room at y = {y}");
    assert!(path.length_m >= (goal - Vec2::new(1.5, 2.0)).norm());
}

#[test]
fn a_door_narrower_than_twice_r_min_is_never_planned_through() {
    // r_min is 0.4 m by default: a 0.7 m door is closed to the planner, a 1.0 m door open.
    for (width, open) in [(0.7, false), (1.0, true)] {
        let mut e = explorer(&room_with_door(width), &INSIDE);
        let step = e.next(at(1.5, 2.0));
        assert_eq!(e.goal().is_some(), open, "door {width} m: {step:?}");
        if !open {
            // Nothing to fly to: hold, and after the confirmation time, done.
            assert_eq!(step, ExploreStep::Waypoint(Vec2::new(1.5, 2.0)));
            e.set_time(1.0);
            assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
            e.set_time(2.5);
            assert_eq!(
                e.next(at(1.5, 2.0)),
                ExploreStep::Done(DoneReason::NoReachableFrontier)
            );
        }
    }
}

#[test]
fn the_way_home_between_two_known_rooms_passes_a_wide_gap_and_never_a_narrow_one() {
    for (width, open) in [(0.7, false), (1.0, true)] {
        // Two 4 m x 4 m rooms side by side, joined by a gap in their shared wall at x = 4.
        let mut walls = room(0.0, 0.0, 8.0, 4.0, &[]);
        walls.push([4.0, 0.0, 4.0, 2.0 - width / 2.0]);
        walls.push([4.0, 2.0 + width / 2.0, 4.0, 4.0]);
        let poses = [
            at(1.0, 1.0),
            at(2.0, 3.0),
            at(3.0, 1.5),
            at(5.0, 2.5),
            at(7.0, 1.0),
            at(6.5, 3.2),
        ];
        let mut e = explorer(&walls, &poses);
        e.set_home(Vec2::new(1.0, 1.0));
        let home = e.path_home(at(7.0, 3.0));
        assert_eq!(home.is_some(), open, "gap {width} m");
        if let Some(path) = home {
            // Through the gap: the straight line (1, 1)-(7, 3) crosses x = 4 at y = 2.
            let crossing = path
                .waypoints
                .windows(2)
                .find(|w| (w[0].x - 4.0) * (w[1].x - 4.0) <= 0.0)
                .unwrap();
            let t = (4.0 - crossing[0].x) / (crossing[1].x - crossing[0].x);
            let y = crossing[0].y + t * (crossing[1].y - crossing[0].y);
            assert!((y - 2.0).abs() < 0.15, "crosses the wall at y = {y}");
            let straight = (Vec2::new(7.0, 3.0) - Vec2::new(1.0, 1.0)).norm();
            assert!(
                path.length_m >= straight && path.length_m < straight + 0.1,
                "{} vs {straight}",
                path.length_m
            );
            assert_eq!(path.waypoints.last(), Some(&Vec2::new(1.0, 1.0)));
        }
    }
}

#[test]
fn a_closed_room_is_done() {
    let mut e = explorer(&room(0.0, 0.0, 5.0, 4.0, &[]), &INSIDE);
    assert!(matches!(e.next(at(2.0, 2.0)), ExploreStep::Waypoint(_)));
    assert_eq!(e.goal(), None);
    e.set_time(2.0);
    assert_eq!(
        e.next(at(2.0, 2.0)),
        ExploreStep::Done(DoneReason::NoReachableFrontier)
    );
    // Done is final, and the way home is still there.
    e.set_home(Vec2::new(1.0, 1.0));
    assert_eq!(
        e.next(at(2.0, 2.0)),
        ExploreStep::Done(DoneReason::NoReachableFrontier)
    );
    let home = e.path_home(at(4.0, 3.0)).unwrap();
    assert!((home.length_m - (3.0f32 * 3.0 + 2.0 * 2.0).sqrt()).abs() < 0.05);
}

#[test]
fn a_vehicle_where_the_map_is_not_drawn_yet_is_not_done() {
    // The map holds the room with the door; the vehicle stands far off in space no keyframe
    // has drawn (it flew on past what the last keyframe saw). That is no sign that nothing is
    // left to explore: the explorer waits for the map instead of ending.
    let mut e = explorer(&room_with_door(1.2), &INSIDE);
    let unmapped = at(30.0, 30.0);
    assert!(matches!(e.next(unmapped), ExploreStep::Waypoint(_)));
    e.set_time(5.0);
    assert!(matches!(e.next(unmapped), ExploreStep::Waypoint(_)));
    // Back in the room the door is still the frontier (planned at the next replanning).
    e.set_time(6.5);
    assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
    assert!(e.goal().unwrap().x > 4.5);
}

#[test]
fn the_edge_of_the_planning_window_is_no_frontier() {
    // A 1 m window in a closed 5 m room: the room beyond the window is known, so nothing is
    // left to explore, and the door case still finds the door beyond the window.
    let config = ExploreConfig {
        plan_window_m: 1.0,
        ..ExploreConfig::default()
    };
    let mut e = explorer_with(config, &room(0.0, 0.0, 5.0, 4.0, &[]), &INSIDE);
    assert!(matches!(e.next(at(2.0, 2.0)), ExploreStep::Waypoint(_)));
    e.set_time(2.0);
    assert_eq!(
        e.next(at(2.0, 2.0)),
        ExploreStep::Done(DoneReason::NoReachableFrontier)
    );
    let mut e = explorer_with(config, &room_with_door(1.2), &INSIDE);
    assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
    assert!(e.goal().unwrap().x > 5.0);
    assert_eq!(e.stats().full_map_plans, 1);
}

#[test]
fn coverage_that_stops_growing_ends_exploration() {
    let mut e = explorer(&room_with_door(1.2), &INSIDE);
    assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
    e.set_time(59.0);
    assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
    e.set_time(60.5);
    assert_eq!(
        e.next(at(1.5, 2.0)),
        ExploreStep::Done(DoneReason::CoverageStalled)
    );
}

#[test]
fn a_star_finds_the_shortest_way_round_a_wall_to_within_a_cell() {
    use plumbline_explore::path::Path;
    use plumbline_explore::search::search;
    use plumbline_slam::grid::{Cell, CellState};
    // 10 m x 10 m of free 0.1 m cells; a wall 0.1 m thick from the bottom edge up to y = 5 m
    // at x = 5.0-5.1 m. The way from A to B goes over the wall's end, kept r from its corners:
    // a tangent to the circle round (5.0, 5.0), an arc, 0.1 m straight over the top, an arc
    // round (5.1, 5.0) and a tangent to B.
    let (n, cell, r) = (100usize, 0.1f32, 0.4f32);
    let states: Vec<CellState> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            if i == 50 && j < 50 {
                CellState::Occupied
            } else {
                CellState::Free
            }
        })
        .collect();
    let mut g = PlanGrid::from_states(Cell::new(0, 0), n, n, cell, states).unwrap();
    g.inflate(r);
    let (a, b) = (Vec2::new(3.05, 3.05), Vec2::new(7.05, 3.05));
    let goal = g.index_of(b).unwrap();
    let found = search(
        &g,
        &[(g.index_of(a).unwrap(), 0.0)],
        |k| k == goal,
        |k| (g.center(k) - b).norm(),
    )
    .unwrap();
    let path = Path::through(&g, a, &found.cells, None);

    let tangent_and_arc = |p: Vec2, c: Vec2| {
        let d = (p - c).norm();
        // The angle at the corner between "down towards p" and "straight up" is pi - below,
        // where below is p's angle under the horizontal; the tangent takes acos(r / d) of it.
        let below = ((c.y - p.y) / d).asin();
        let turn = core::f32::consts::PI - (core::f32::consts::FRAC_PI_2 - below) - (r / d).acos();
        (d * d - r * r).sqrt() + r * turn
    };
    let truth =
        tangent_and_arc(a, Vec2::new(5.0, 5.0)) + 0.1 + tangent_and_arc(b, Vec2::new(5.1, 5.0));
    assert!(
        (path.length_m - truth).abs() <= cell,
        "planned {} m, shortest {truth} m",
        path.length_m
    );
    // The search's own cost is the grid's eight-direction length, never shorter.
    assert!(found.cost_m >= path.length_m - 1e-3);
    // And the path stays on safe cells: no corner of it comes closer to the wall's box than
    // r less half a cell's diagonal.
    for p in &path.waypoints {
        let dx = (5.0 - p.x).max(p.x - 5.1).max(0.0);
        let dy = (p.y - 5.0).max(0.0);
        assert!(
            dx.hypot(dy) >= r - 0.5 * cell * core::f32::consts::SQRT_2,
            "{p:?}"
        );
    }
}

#[test]
fn a_pose_that_is_not_finite_holds_the_last_position() {
    let mut e = explorer(&room_with_door(1.2), &INSIDE);
    assert!(matches!(e.next(at(1.5, 2.0)), ExploreStep::Waypoint(_)));
    assert_eq!(
        e.next(Pose2::new(f32::NAN, 2.0, 0.0)),
        ExploreStep::Waypoint(Vec2::new(1.5, 2.0))
    );
    assert_eq!(e.path_home(Pose2::new(f32::INFINITY, 0.0, 0.0)), None);
}

#[test]
fn a_place_the_vehicle_was_stuck_at_is_planned_round_and_a_way_with_none_left_is_none() {
    // Two 4 m x 4 m rooms side by side; the wall between them (x = 4) has a 1.2 m door low
    // (y 0.4 to 1.6) and one high (y 2.4 to 3.6). Home is in the left room, the vehicle in the
    // right one, both low: the way home is through the low door, 6 m.
    let mut walls = room(0.0, 0.0, 8.0, 4.0, &[]);
    walls.extend([
        [4.0, 0.0, 4.0, 0.4],
        [4.0, 1.6, 4.0, 2.4],
        [4.0, 3.6, 4.0, 4.0],
    ]);
    // Scans from inside the rooms (a pose on the wall's line would see it edge on).
    let poses = [
        at(1.0, 1.0),
        at(2.0, 3.0),
        at(6.0, 3.0),
        at(7.0, 1.0),
        at(3.0, 2.0),
        at(5.0, 2.0),
    ];
    let mut e = explorer(&walls, &poses);
    e.set_home(Vec2::new(1.0, 1.0));
    let low = e.path_home(at(7.0, 1.0)).unwrap();
    assert!((low.length_m - 6.0).abs() < 0.1, "{low:?}");
    // Stuck in the low door: the way home is through the high one, at its lowest point that
    // keeps the preferred clearance (y = 2.4 + 0.5 = 2.9): (7,1) to (4,2.9) to (1,1), 7.1 m,
    // give or take a cell.
    e.block(Vec2::new(4.0, 1.0));
    let high = e.path_home(at(7.0, 1.0)).unwrap();
    let preferred = ExploreConfig::default().preferred_clearance_m;
    let via_high = 2.0 * 3.0f32.hypot(1.4 + preferred);
    assert!((high.length_m - via_high).abs() < 0.15, "{high:?}");
    assert!(high
        .waypoints
        .iter()
        .all(|w| (*w - Vec2::new(4.0, 1.0)).norm() > 1.0));
    // Stuck there too: no way home is left.
    e.block(Vec2::new(4.0, 3.0));
    assert_eq!(e.path_home(at(7.0, 1.0)), None);
}

#[test]
fn off_the_centre_line_of_a_corridor_being_explored_the_look_ahead_is_not_cut_short() {
    // A 2 m corridor running on past the lidar's range: the frontier lies down it. A weaving
    // vehicle 0.45 m from a wall stands nearer than plans like to keep (0.5 m), and its
    // waypoint must still be a full look-ahead on along the path: held back to what the grid
    // shows in sight from there, it came back to the vehicle and the flight crawled.
    let walls = vec![
        [0.0, 0.0, 30.0, 0.0],
        [0.0, 2.0, 30.0, 2.0],
        [0.0, 0.0, 0.0, 2.0],
    ];
    let from = at(1.5, 0.45);
    let mut e = explorer(&walls, &[at(1.0, 1.0), from]);
    let ExploreStep::Waypoint(w) = e.next(from) else {
        panic!("a corridor to explore is not done");
    };
    let goal = e.goal().unwrap();
    assert!(
        goal.x > from.x + 1.0,
        "goal {goal:?} is not down the corridor"
    );
    let ahead = (w - Vec2::new(from.x, from.y)).norm();
    let lookahead_m = ExploreConfig::default().lookahead_m;
    assert!(
        ahead > 0.9 * lookahead_m,
        "look-ahead {ahead:.2} m, at {w:?}"
    );
}
