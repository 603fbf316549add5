//! Shortest paths over the safe cells of a planning grid: A* (Dijkstra when the heuristic is
//! zero), eight neighbours, never cutting the corner of an unsafe cell. A step costs its length
//! times the grid's step cost of the cell it enters (more where the preferred clearance is not
//! kept), so the path is the cheapest, which is the shortest where the map has room.

use crate::plan_grid::PlanGrid;
use plumbline_core::geom::Vec2;
use plumbline_slam::grid::CellState;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The cells of a cheapest path, from a start cell to the first goal cell reached, and its
/// cost (the entry cost of the start plus the weighted cell steps), m.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub cells: Vec<usize>,
    pub cost_m: f32,
}

/// A heap entry ordered by smallest estimate first.
#[derive(Clone, Copy, PartialEq)]
struct Open {
    estimate: f32,
    cell: usize,
}

impl Eq for Open {}

impl Ord for Open {
    fn cmp(&self, o: &Self) -> Ordering {
        o.estimate
            .total_cmp(&self.estimate)
            .then(o.cell.cmp(&self.cell))
    }
}

impl PartialOrd for Open {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Searches from `starts` (cells with the cost of getting to them, m) over safe cells to the
/// cheapest cell where `is_goal` holds. `heuristic` must never exceed the true remaining cost
/// (the straight-line distance never does; zero gives Dijkstra and the nearest goal by
/// weighted path length).
pub fn search(
    g: &PlanGrid,
    starts: &[(usize, f32)],
    is_goal: impl Fn(usize) -> bool,
    heuristic: impl Fn(usize) -> f32,
) -> Option<Found> {
    let mut cost = vec![f32::INFINITY; g.len()];
    let mut parent = vec![usize::MAX; g.len()];
    let mut closed = vec![false; g.len()];
    let mut open = BinaryHeap::new();
    for &(cell, c) in starts {
        if cell < g.len() && g.is_safe(cell) && c < cost[cell] {
            cost[cell] = c;
            open.push(Open {
                estimate: c + heuristic(cell),
                cell,
            });
        }
    }
    let step = g.cell_m();
    let diagonal = step * core::f32::consts::SQRT_2;
    while let Some(Open { cell, .. }) = open.pop() {
        if std::mem::replace(&mut closed[cell], true) {
            continue; // a stale entry of a cell already expanded at a lower cost
        }
        if is_goal(cell) {
            let mut cells = vec![cell];
            while let Some(&p) = cells
                .last()
                .map(|&c| &parent[c])
                .filter(|&&p| p != usize::MAX)
            {
                cells.push(p);
            }
            cells.reverse();
            return Some(Found {
                cells,
                cost_m: cost[cell],
            });
        }
        let (i, j) = g.coords(cell);
        for dj in -1..=1 {
            for di in -1i32..=1 {
                if di == 0 && dj == 0 {
                    continue;
                }
                let Some(n) = g.index(i + di, j + dj) else {
                    continue;
                };
                if !g.is_safe(n) {
                    continue;
                }
                let d = if di != 0 && dj != 0 {
                    let side = |a, b| g.index(a, b).is_some_and(|k| g.is_safe(k));
                    if !(side(i + di, j) && side(i, j + dj)) {
                        continue;
                    }
                    diagonal
                } else {
                    step
                };
                let c = cost[cell] + d * g.step_cost(n);
                if c < cost[n] {
                    cost[n] = c;
                    parent[n] = cell;
                    open.push(Open {
                        estimate: c + heuristic(n),
                        cell: n,
                    });
                }
            }
        }
    }
    None
}

/// Where a search may begin from point `p`: its own cell if that is safe, else the safe cells
/// within `reach_m` that a straight leg over free cells reaches (the vehicle drifted closer
/// than `r_min` to a wall, or the map grew an obstacle next to it), each with the leg's
/// length. Empty when `p` is off the map or boxed in.
pub fn entries(g: &PlanGrid, p: Vec2, reach_m: f32) -> Vec<(usize, f32)> {
    let Some(own) = g.index_of(p) else {
        return Vec::new();
    };
    if g.is_safe(own) {
        return vec![(own, 0.0)];
    }
    let (i, j) = g.coords(own);
    let r = (reach_m / g.cell_m()).ceil() as i32;
    let mut out = Vec::new();
    for dj in -r..=r {
        for di in -r..=r {
            let Some(n) = g.index(i + di, j + dj) else {
                continue;
            };
            let d = (g.center(n) - p).norm();
            if g.is_safe(n)
                && d <= reach_m
                && g.segment_clear(p, g.center(n), |k| g.state(k) == CellState::Free)
            {
                out.push((n, d));
            }
        }
    }
    out
}
