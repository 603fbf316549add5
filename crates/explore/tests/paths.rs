//! Properties of planned paths on random obstacle fields: every leg of a path stays on safe
//! cells, pulling it taut never lengthens the grid's path, and no path is shorter than the
//! straight line.

use plumbline_core::geom::Vec2;
use plumbline_explore::path::Path;
use plumbline_explore::plan_grid::PlanGrid;
use plumbline_explore::search::search;
use plumbline_slam::grid::{Cell, CellState};
use proptest::prelude::*;

const N: usize = 40;

proptest! {
    #[test]
    fn paths_stay_safe_and_are_no_longer_than_the_grid_path(
        obstacles in prop::collection::vec((0..N, 0..N), 0..40),
        from in (0..N, 0..N),
        to in (0..N, 0..N),
        r in 0.05f32..0.3,
    ) {
        let mut states = vec![CellState::Free; N * N];
        for &(i, j) in &obstacles {
            states[j * N + i] = CellState::Occupied;
        }
        let mut g = PlanGrid::from_states(Cell::new(0, 0), N, N, 0.1, states).unwrap();
        g.inflate(r);
        let (a, b) = (from.1 * N + from.0, to.1 * N + to.0);
        prop_assume!(g.is_safe(a) && g.is_safe(b));
        let goal = g.center(b);
        let found = search(&g, &[(a, 0.0)], |k| k == b, |k| (g.center(k) - goal).norm());
        if let Some(found) = found {
            let path = Path::through(&g, g.center(a), &found.cells, None);
            prop_assert_eq!(path.waypoints.first(), Some(&g.center(a)));
            prop_assert_eq!(path.waypoints.last(), Some(&goal));
            for leg in path.waypoints.windows(2) {
                prop_assert!(g.segment_clear(leg[0], leg[1], |k| g.is_safe(k)), "{:?}", leg);
            }
            prop_assert!(path.length_m <= found.cost_m + 1e-3, "{} > {}", path.length_m, found.cost_m);
            prop_assert!(path.length_m >= (goal - g.center(a)).norm() - 1e-3);
            let ahead = path.lookahead(g.center(a), 0.5);
            prop_assert!(ahead.is_finite());
            prop_assert!((ahead - g.center(a)).norm() <= 0.5 + 1e-3);
        }
    }
}

#[test]
fn unreachable_goals_give_no_path() {
    // A wall across the whole grid.
    let states: Vec<CellState> = (0..N * N)
        .map(|k| {
            if k % N == 20 {
                CellState::Occupied
            } else {
                CellState::Free
            }
        })
        .collect();
    let mut g = PlanGrid::from_states(Cell::new(0, 0), N, N, 0.1, states).unwrap();
    g.inflate(0.2);
    let b = 5 * N + 35;
    assert!(search(&g, &[(5 * N + 5, 0.0)], |k| k == b, |_| 0.0).is_none());
    let _ = Vec2::ZERO;
}

/// A wall across x = 2.0..2.1 m with a door of `door_cells` cells from y = 1.4 m, planned with
/// `r_min` 0.4 m and the given preferred clearance; the path from below-left of the door to
/// below-right of it and its least distance from an occupied cell's square.
fn through_door(door_cells: usize, preferred_m: f32) -> Option<(Path, f32)> {
    let door = 14..14 + door_cells;
    let occupied = |i: usize, j: usize| i == 20 && !door.contains(&j);
    let states: Vec<CellState> = (0..N * N)
        .map(|k| match occupied(k % N, k / N) {
            true => CellState::Occupied,
            false => CellState::Free,
        })
        .collect();
    let mut g = PlanGrid::from_states(Cell::new(0, 0), N, N, 0.1, states).unwrap();
    g.inflate(0.4);
    g.prefer(preferred_m, 4.0);
    let (a, b) = (5 * N + 10, 5 * N + 32);
    let goal = g.center(b);
    let found = search(&g, &[(a, 0.0)], |k| k == b, |k| (g.center(k) - goal).norm())?;
    let path = Path::through(&g, g.center(a), &found.cells, None);
    let square_gap = |p: Vec2, i: usize, j: usize| {
        let dx = (p.x - (i as f32 + 0.5) * 0.1).abs() - 0.05;
        let dy = (p.y - (j as f32 + 0.5) * 0.1).abs() - 0.05;
        dx.max(0.0).hypot(dy.max(0.0))
    };
    let mut least = f32::INFINITY;
    for s in 0..=(path.length_m / 0.01) as usize {
        let p = path.point_at(s as f32 * 0.01);
        for j in (0..N).filter(|&j| occupied(20, j)) {
            least = least.min(square_gap(p, 20, j));
        }
    }
    Some((path, least))
}

#[test]
fn paths_keep_the_preferred_clearance_round_a_door_and_still_pass_a_narrower_one() {
    // Round the jambs of a 1.2 m door the path keeps the preferred 0.5 m (less half a cell's
    // diagonal); planned on r_min alone it hugs them at 0.4 m.
    let half_diagonal = 0.05 * std::f32::consts::SQRT_2;
    let (_, roomy) = through_door(12, 0.5).unwrap();
    assert!(roomy >= 0.5 - half_diagonal, "{roomy}");
    let (_, tight) = through_door(12, 0.4).unwrap();
    assert!(tight < 0.45, "{tight}");
    // A 0.9 m door has no cell 0.5 m from both jambs: it is still passed, at r_min.
    let (path, narrow) = through_door(9, 0.5).expect("the 0.9 m door was lost");
    assert!(narrow >= 0.4 - half_diagonal, "{narrow}");
    assert!(path.waypoints.iter().any(|p| p.x > 2.1));
}

#[test]
fn the_lookahead_in_sight_stops_short_of_a_corner() {
    let path = Path::new(vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(2.0, 0.0),
        Vec2::new(2.0, 2.0),
    ]);
    let from = Vec2::new(1.5, 0.0);
    assert_eq!(path.lookahead(from, 1.0), Vec2::new(2.0, 0.5));
    // Only points near the first leg are in sight: the point comes back to the corner.
    let near = path.lookahead_in_sight(from, 1.0, 0.1, |_, b| b.y < 0.25);
    assert!((near - Vec2::new(2.0, 0.2)).norm() < 1e-4, "{near:?}");
    // Nothing in sight: one step ahead, back on the path.
    let step = path.lookahead_in_sight(from, 1.0, 0.1, |_, _| false);
    assert!((step - Vec2::new(1.6, 0.0)).norm() < 1e-4, "{step:?}");
}
