//! Map error (DESIGN.md §6): how far the occupied cells of a map lie from the walls the
//! simulator really built. Only a simulation knows the walls exactly, so this is where a SLAM
//! map is scored against the truth; the map frame is tied to the world by the true pose of the
//! vehicle when the map started (SLAM's map frame is its first scan's pose).

use crate::world::scene::Scene;
use crate::world::World;
use plumbline_slam::grid::OccupancyGrid;

/// The figures of one map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapError {
    /// Occupied cells scored.
    pub occupied_cells: usize,
    /// Mean distance from an occupied cell's centre to the nearest wall, m.
    pub mean_m: f64,
    /// Fraction of occupied cells whose centre is more than two cells from every wall: the
    /// cells that are not a slightly blurred wall but something in the wrong place.
    pub far_fraction: f64,
    /// The distance below which 95 % of the cells lie, m.
    pub p95_m: f64,
}

/// Searching this far through the scene's wall index answers almost every cell of a sane map;
/// cells farther from any wall are measured against every wall.
const SEARCH_M: f64 = 1.0;

/// Scores occupied cell centres given in the map frame. `map_in_world` is the world pose
/// (x, y, yaw) of the map frame's origin; `resolution_m` sets the two-cell limit of
/// [`MapError::far_fraction`]. `None` when there is no cell to score.
pub fn map_error(
    centres_in_map: impl IntoIterator<Item = [f64; 2]>,
    resolution_m: f64,
    world: &World,
    map_in_world: [f64; 3],
) -> Option<MapError> {
    let scene = Scene::new(world);
    let (s, c) = map_in_world[2].sin_cos();
    let mut distances: Vec<f64> = centres_in_map
        .into_iter()
        .map(|[x, y]| {
            let p = [
                c * x - s * y + map_in_world[0],
                s * x + c * y + map_in_world[1],
            ];
            let near = scene.clearance(p, SEARCH_M);
            if near < SEARCH_M {
                near
            } else {
                world.clearance(p)
            }
        })
        .collect();
    if distances.is_empty() {
        return None;
    }
    let n = distances.len();
    let mean_m = distances.iter().sum::<f64>() / n as f64;
    let far = distances
        .iter()
        .filter(|&&d| d > 2.0 * resolution_m)
        .count();
    distances.sort_unstable_by(f64::total_cmp);
    Some(MapError {
        occupied_cells: n,
        mean_m,
        far_fraction: far as f64 / n as f64,
        p95_m: distances[((n - 1) as f64 * 0.95).round() as usize],
    })
}

/// [`map_error`] of a grid's occupied cells.
pub fn grid_map_error(
    grid: &OccupancyGrid,
    world: &World,
    map_in_world: [f64; 3],
) -> Option<MapError> {
    let frame = grid.frame();
    map_error(
        grid.occupied_cells().map(|cell| {
            let p = frame.center(cell);
            [f64::from(p.x), f64::from(p.y)]
        }),
        f64::from(frame.resolution_m()),
        world,
        map_in_world,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_room() -> World {
        World::parse("start 1 1 0\noutline 0 0 4 0 4 3 0 3\n").unwrap()
    }

    /// Points on the room's walls, in the frame of a map whose origin is at `map_in_world`.
    fn wall_points_in_map(map_in_world: [f64; 3], off_m: f64) -> Vec<[f64; 2]> {
        let (s, c) = map_in_world[2].sin_cos();
        // Half a metre clear of the corners, so each point's nearest wall is its own.
        (5..35)
            .map(|k| [k as f64 * 0.1, off_m])
            .chain((5..25).map(|k| [4.0 - off_m, k as f64 * 0.1]))
            .map(|[x, y]| {
                let (dx, dy) = (x - map_in_world[0], y - map_in_world[1]);
                [c * dx + s * dy, -s * dx + c * dy]
            })
            .collect()
    }

    #[test]
    fn cells_on_the_walls_score_zero_and_shifted_cells_their_shift() {
        let w = square_room();
        let start = [1.0, 1.0, 0.7];
        let on = map_error(wall_points_in_map(start, 0.0), 0.05, &w, start).unwrap();
        assert_eq!(on.occupied_cells, 50);
        assert!(on.mean_m < 1e-9 && on.far_fraction == 0.0, "{on:?}");
        let off = map_error(wall_points_in_map(start, 0.3), 0.05, &w, start).unwrap();
        assert!((off.mean_m - 0.3).abs() < 1e-9, "{off:?}");
        assert_eq!(off.far_fraction, 1.0);
        let near = map_error(wall_points_in_map(start, 0.08), 0.05, &w, start).unwrap();
        assert_eq!(near.far_fraction, 0.0, "0.08 m is within two 5 cm cells");
        // The same cells scored with a map pose 0.2 m off along y: the cells on the y = 0
        // wall move 0.2 m away from it, those on the x = 4 wall slide along it.
        let wrong = map_error(wall_points_in_map(start, 0.0), 0.05, &w, [1.0, 1.2, 0.7]).unwrap();
        assert!((wrong.mean_m - 0.2 * 30.0 / 50.0).abs() < 1e-9, "{wrong:?}");
        assert_eq!(map_error(Vec::new(), 0.05, &w, start), None);
    }

    #[test]
    fn cells_far_from_every_wall_are_measured_exactly() {
        let w = World::parse("start 1 1 0\noutline 0 0 40 0 40 30 0 30\n").unwrap();
        let e = map_error([[20.0, 15.0]], 0.05, &w, [0.0; 3]).unwrap();
        assert!(
            (e.mean_m - 15.0).abs() < 1e-9 && e.p95_m == e.mean_m,
            "{e:?}"
        );
    }
}
