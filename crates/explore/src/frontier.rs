//! Frontiers: free cells with an unknown cell beside them, where flying on shows something
//! new, grouped into clusters of touching cells.

use crate::plan_grid::PlanGrid;
use plumbline_core::geom::Vec2;
use plumbline_slam::grid::CellState;

/// One connected run of frontier cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Planning-grid indices of the cells.
    pub cells: Vec<usize>,
    /// Mean of the cell centres, m.
    pub centroid: Vec2,
}

/// All frontier clusters, and for each cell the cluster it belongs to.
pub struct Frontiers {
    pub clusters: Vec<Cluster>,
    /// `cluster_of[k]`: index into `clusters` of cell `k`'s cluster, `u32::MAX` if none.
    pub cluster_of: Vec<u32>,
}

pub const NO_CLUSTER: u32 = u32::MAX;

/// Whether cell `k` is a frontier: free, with an unknown cell above, below, left or right.
/// (The diagonal is left out: behind a wall's corner it would make every corner a frontier.)
pub fn is_frontier(g: &PlanGrid, k: usize) -> bool {
    let (i, j) = g.coords(k);
    frontier_at(g, i, j, k)
}

/// [`is_frontier`] of cell `k` at column `i`, row `j`.
fn frontier_at(g: &PlanGrid, i: i32, j: i32, k: usize) -> bool {
    if g.state(k) != CellState::Free || !g.in_core_at(i, j) {
        return false;
    }
    [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(di, dj)| {
        g.index(i + di, j + dj)
            .is_some_and(|n| g.state(n) == CellState::Unknown)
    })
}

/// The frontier clusters of at least `min_cells` cells (touching in the eight directions).
pub fn clusters(g: &PlanGrid, min_cells: usize) -> Frontiers {
    let (w, h) = (g.width() as i32, g.height() as i32);
    let frontier: Vec<bool> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .enumerate()
        .map(|(k, (i, j))| frontier_at(g, i, j, k))
        .collect();
    let mut cluster_of = vec![NO_CLUSTER; g.len()];
    let mut seen = vec![false; g.len()];
    let mut clusters = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..g.len() {
        if !frontier[seed] || seen[seed] {
            continue;
        }
        seen[seed] = true;
        stack.push(seed);
        let mut cells = Vec::new();
        while let Some(k) = stack.pop() {
            cells.push(k);
            let (i, j) = g.coords(k);
            for dj in -1..=1 {
                for di in -1..=1 {
                    if let Some(n) = g.index(i + di, j + dj) {
                        if frontier[n] && !seen[n] {
                            seen[n] = true;
                            stack.push(n);
                        }
                    }
                }
            }
        }
        if cells.len() >= min_cells.max(1) {
            let sum = cells.iter().fold(Vec2::ZERO, |acc, &k| acc + g.center(k));
            let label = clusters.len() as u32;
            for &k in &cells {
                cluster_of[k] = label;
            }
            clusters.push(Cluster {
                centroid: sum * (1.0 / cells.len() as f32),
                cells,
            });
        }
    }
    Frontiers {
        clusters,
        cluster_of,
    }
}
