//! The planning grid reads the map a row at a time; each planning cell must still hold the
//! state its block of map cells gives when every map cell is asked on its own.

mod common;

use common::{explorer, Wall};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_explore::plan_grid::{block_state, PlanGrid};
use plumbline_explore::ExploreConfig;
use plumbline_slam::grid::Cell;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random walls seen from random poses, over the whole map and within a window.
    #[test]
    fn every_planning_cell_is_its_blocks_state(
        walls in proptest::collection::vec(
            (-6.0f32..6.0, -6.0f32..6.0, -3.0f32..3.0, -3.0f32..3.0), 1..12),
        poses in proptest::collection::vec((-3.0f32..3.0, -3.0f32..3.0, -3.2f32..3.2), 1..4),
        window in proptest::option::of((-4.0f32..4.0, -4.0f32..4.0, 0.5f32..5.0)),
    ) {
        let walls: Vec<Wall> = walls
            .iter()
            .map(|&(x, y, dx, dy)| [x, y, x + dx, y + dy])
            .collect();
        let poses: Vec<Pose2> = poses.iter().map(|&(x, y, t)| Pose2::new(x, y, t)).collect();
        let e = explorer(&walls, &poses);
        let grid = e.map().grid();
        let config = ExploreConfig::default();
        let factor = config.plan_factor();
        let window = window.map(|(x, y, half)| (Vec2::new(x, y), half));
        let plan = PlanGrid::new(grid, factor, config.clearance(), window);
        // A window that misses the map gives the one-cell plan of an empty map, placed nowhere.
        prop_assume!(plan.len() > 1);
        for k in 0..plan.len() {
            let fine = grid.frame().cell_of(plan.center(k));
            let corner = Cell::new(
                fine.i.div_euclid(factor) * factor,
                fine.j.div_euclid(factor) * factor,
            );
            prop_assert_eq!(plan.state(k), block_state(grid, corner, factor), "cell {}", k);
        }
    }
}
