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
