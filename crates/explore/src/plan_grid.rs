//! The grid planners search: the live map in coarser cells, with every obstacle grown by
//! `r_min` so that a path of cell centres keeps the vehicle clear.
//!
//! A planning cell is occupied if any of its map cells is, else free if any is, else unknown:
//! obstacles are never thinned away by the coarser cells, and the single unknown cells that
//! fall between far beams do not break up free space. A free cell is *safe* when no occupied
//! cell's square comes within `r_min` of its centre; measuring to the square rather than the
//! centre means the grid can only make a gap look narrower than it is, never wider, so a gap
//! narrower than `2 r_min` never has a safe cell in it.
//!
//! A safe cell is also *roomy* when it keeps the preferred clearance ([`PlanGrid::prefer`]),
//! the clearance guard's own radius: searches charge more for a step onto a safe cell that is
//! not roomy, so paths keep the guard's clearance wherever the map has room and come as close as
//! `r_min` only where they must (a door narrower than twice the preferred clearance), and the
//! guard does not have to fight the path round every corner.

use plumbline_core::geom::Vec2;
use plumbline_slam::grid::{Cell, CellState, OccupancyGrid};

pub struct PlanGrid {
    /// Planning-cell index of column 0, row 0.
    origin: Cell,
    width: usize,
    height: usize,
    cell_m: f32,
    states: Vec<CellState>,
    safe: Vec<bool>,
    /// Safe and at least the preferred clearance from every obstacle.
    roomy: Vec<bool>,
    /// Cost of a step onto a safe cell that is not roomy, per metre of step.
    tight_cost: f32,
    free_cells: usize,
    /// Width of the border that is never safe and never a frontier, cells.
    margin: usize,
}

impl PlanGrid {
    /// The planning grid of `grid` with cells of `factor` map cells a side and obstacles
    /// grown by `r_min_m`: over the whole map, or only over the square of half-side `half_m`
    /// round `centre` when a window is given (planning work then stays bounded however large
    /// the map grows). A border of cells wide enough to hold every obstacle that reaches in
    /// lies round the planned area: it is never safe and never a frontier, so the edge of a
    /// window is not taken for the edge of the map, while the map's own edge still is.
    pub fn new(
        grid: &OccupancyGrid,
        factor: i32,
        clearance: Clearance,
        window: Option<(Vec2, f32)>,
    ) -> Self {
        let r_min_m = clearance.r_min_m;
        let cell_m = grid.frame().resolution_m() * factor as f32;
        let Some(bounds) = grid.bounds() else {
            return Self::unknown(cell_m);
        };
        let coarse = |c: Cell| Cell::new(c.i.div_euclid(factor), c.j.div_euclid(factor));
        let (mut lo, mut hi) = (coarse(bounds.min), coarse(bounds.max));
        if let Some((centre, half_m)) = window {
            let at = |v: f32| (v / cell_m).floor().clamp(-1e9, 1e9) as i32;
            let half = (half_m / cell_m).ceil().min(1e9) as i32;
            let (ci, cj) = (at(centre.x), at(centre.y));
            lo = Cell::new(lo.i.max(ci - half), lo.j.max(cj - half));
            hi = Cell::new(hi.i.min(ci + half), hi.j.min(cj + half));
            if lo.i > hi.i || lo.j > hi.j {
                return Self::unknown(cell_m);
            }
        }
        let margin = (r_min_m / cell_m).ceil() as i32 + 1;
        let origin = Cell::new(lo.i - margin, lo.j - margin);
        let width = (hi.i - lo.i + 1 + 2 * margin) as usize;
        let height = (hi.j - lo.j + 1 + 2 * margin) as usize;
        let mut states = vec![CellState::Unknown; width * height];
        let fine_lo = Cell::new(
            (origin.i * factor).max(bounds.min.i),
            (origin.j * factor).max(bounds.min.j),
        );
        let fine_hi = Cell::new(
            ((origin.i + width as i32) * factor - 1).min(bounds.max.i),
            ((origin.j + height as i32) * factor - 1).min(bounds.max.j),
        );
        // The planning column is carried along the row rather than divided out of each map
        // cell's column, and the map's states are read a row at a time (a tile looked up once
        // per run of cells in it rather than once a cell).
        let first_column = (fine_lo.i.div_euclid(factor) - origin.i) as usize;
        let first_sub = fine_lo.i.rem_euclid(factor);
        let mut fine_row = Vec::with_capacity((fine_hi.i - fine_lo.i + 1).max(0) as usize);
        for j in fine_lo.j..=fine_hi.j {
            let row = (j.div_euclid(factor) - origin.j) as usize * width;
            let (mut k, mut sub) = (row + first_column, first_sub);
            fine_row.clear();
            grid.row_states(j, fine_lo.i, fine_hi.i, &mut fine_row);
            for &state in &fine_row {
                states[k] = merge(states[k], state);
                sub += 1;
                if sub == factor {
                    (k, sub) = (k + 1, 0);
                }
            }
        }
        let mut plan = Self::from_states(origin, width, height, cell_m, states)
            .unwrap_or_else(|| Self::unknown(cell_m));
        plan.inflate(r_min_m);
        plan.prefer(clearance.preferred_m, clearance.tight_cost);
        plan.set_border(margin as usize);
        plan
    }

    /// Makes the outer `margin` cells all round unsafe and no frontier.
    fn set_border(&mut self, margin: usize) {
        self.margin = margin;
        let (w, h) = (self.width, self.height);
        for j in 0..h {
            let row = j * w;
            let edge = j < margin || j + margin >= h;
            let (left, right) = if edge {
                (0..w, 0..0)
            } else {
                (
                    0..margin.min(w),
                    w.saturating_sub(margin).max(margin.min(w))..w,
                )
            };
            for i in left.chain(right) {
                self.safe[row + i] = false;
                self.roomy[row + i] = false;
            }
        }
    }

    /// Whether the cell at column `i`, row `j` (inside the grid) lies inside the border (see
    /// [`Self::new`]).
    pub fn in_core_at(&self, i: i32, j: i32) -> bool {
        let (i, j, m) = (i as usize, j as usize, self.margin);
        i >= m && j >= m && i + m < self.width && j + m < self.height
    }

    /// One unknown cell: the plan of an empty map.
    fn unknown(cell_m: f32) -> Self {
        Self {
            origin: Cell::new(0, 0),
            width: 1,
            height: 1,
            cell_m,
            states: vec![CellState::Unknown],
            safe: vec![false],
            roomy: vec![false],
            tight_cost: 1.0,
            free_cells: 0,
            margin: 0,
        }
    }

    /// A planning grid from cell states given row by row (row 0 at the bottom), with no
    /// obstacle growth yet (every free cell safe and roomy); `origin` is the planning-cell
    /// index of the first cell. `None`
    /// unless there is one state per cell and the cell size is finite and positive.
    pub fn from_states(
        origin: Cell,
        width: usize,
        height: usize,
        cell_m: f32,
        states: Vec<CellState>,
    ) -> Option<Self> {
        if states.len() != width.checked_mul(height)? || !(cell_m.is_finite() && cell_m > 0.0) {
            return None;
        }
        let safe: Vec<bool> = states.iter().map(|&s| s == CellState::Free).collect();
        let free_cells = safe.iter().filter(|&&s| s).count();
        Some(Self {
            origin,
            width,
            height,
            cell_m,
            states,
            roomy: safe.clone(),
            tight_cost: 1.0,
            safe,
            free_cells,
            margin: 0,
        })
    }

    /// Marks unsafe every free cell whose centre lies within `r_min_m` of an occupied cell's
    /// square.
    pub fn inflate(&mut self, r_min_m: f32) {
        let mut unsafe_cells = vec![false; self.len()];
        self.mark_within(r_min_m, &mut unsafe_cells);
        for (k, near) in unsafe_cells.into_iter().enumerate() {
            if near {
                self.safe[k] = false;
                self.roomy[k] = false;
            }
        }
    }

    /// Marks not roomy every cell whose centre lies within `preferred_m` of an occupied cell's
    /// square, and makes a step onto a safe cell that is not roomy cost `tight_cost` (at least
    /// 1) times its length.
    pub fn prefer(&mut self, preferred_m: f32, tight_cost: f32) {
        let mut near = vec![false; self.len()];
        self.mark_within(preferred_m, &mut near);
        for (roomy, near) in self.roomy.iter_mut().zip(near) {
            *roomy &= !near;
        }
        self.tight_cost = tight_cost.max(1.0);
    }

    /// Sets `out[k]` for every cell whose centre lies within `radius_m` of an occupied cell's
    /// square.
    fn mark_within(&self, radius_m: f32, out: &mut [bool]) {
        let reach = (radius_m / self.cell_m).ceil() as i32 + 1;
        // The gap to a square grows with the column offset, so each row of the disc is one
        // run of columns, `-half..=half` (none where `half` is negative): a cell marks its
        // disc a run at a time.
        let gap = |d: i32| ((d.abs() as f32) - 0.5).max(0.0) * self.cell_m;
        let rows: Vec<(i32, i32)> = (-reach..=reach)
            .map(|dj| {
                let half = (0..=reach)
                    .take_while(|&di| gap(di).hypot(gap(dj)) < radius_m)
                    .last()
                    .unwrap_or(-1);
                (dj, half)
            })
            .filter(|&(_, half)| half >= 0)
            .collect();
        let (w, h) = (self.width as i32, self.height as i32);
        for (k, _) in self
            .states
            .iter()
            .enumerate()
            .filter(|(_, &s)| s == CellState::Occupied)
        {
            let (i, j) = self.coords(k);
            for &(dj, half) in &rows {
                let row = j + dj;
                if row < 0 || row >= h {
                    continue;
                }
                let (lo, hi) = ((i - half).max(0), (i + half).min(w - 1));
                if lo <= hi {
                    let at = row as usize * self.width;
                    out[at + lo as usize..=at + hi as usize].fill(true);
                }
            }
        }
    }

    /// Marks unsafe every cell whose centre lies within `radius_m` of each of `places`: where
    /// the vehicle could not get through although the map shows free space (a gap in a wall
    /// the scans never closed, a person in a door).
    pub fn block(&mut self, places: &[Vec2], radius_m: f32) {
        if places.is_empty() {
            return;
        }
        for k in 0..self.safe.len() {
            let c = self.center(k);
            if places.iter().any(|&q| (c - q).norm() <= radius_m) {
                self.safe[k] = false;
                self.roomy[k] = false;
            }
        }
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn len(&self) -> usize {
        self.states.len()
    }

    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    pub fn cell_m(&self) -> f32 {
        self.cell_m
    }

    pub fn state(&self, k: usize) -> CellState {
        self.states[k]
    }

    /// Free and at least `r_min` from every mapped obstacle.
    pub fn is_safe(&self, k: usize) -> bool {
        self.safe[k]
    }

    /// Safe and at least the preferred clearance from every mapped obstacle.
    pub fn is_roomy(&self, k: usize) -> bool {
        self.roomy[k]
    }

    /// Cost per metre of a step onto cell `k`: 1 on a roomy cell, the tight cost on a safe
    /// cell that is not roomy.
    pub fn step_cost(&self, k: usize) -> f32 {
        if self.roomy[k] {
            1.0
        } else {
            self.tight_cost
        }
    }

    /// Whether a straight leg from `a` to `b` may be flown: it crosses safe cells only, and
    /// between its end cells keeps to roomy ones unless both ends lie on cells that are not
    /// roomy (a leg inside a door). A leg from roomy space into a tight place therefore
    /// follows the searched cells rather than cutting the corner the preferred clearance goes
    /// round.
    pub fn leg_clear(&self, a: Vec2, b: Vec2) -> bool {
        let (ka, kb) = (self.index_of(a), self.index_of(b));
        let tight = |k: Option<usize>| k.is_some_and(|k| !self.roomy[k]);
        let inside = tight(ka) && tight(kb);
        self.segment_clear(a, b, |k| {
            self.safe[k] && (self.roomy[k] || inside || Some(k) == ka || Some(k) == kb)
        })
    }

    /// Known free area in the planned area and its border, m².
    pub fn free_area_m2(&self) -> f32 {
        self.free_cells as f32 * self.cell_m * self.cell_m
    }

    /// Column and row of cell `k` in this grid.
    pub fn coords(&self, k: usize) -> (i32, i32) {
        ((k % self.width) as i32, (k / self.width) as i32)
    }

    /// The index of column `i`, row `j`, if inside.
    pub fn index(&self, i: i32, j: i32) -> Option<usize> {
        (i >= 0 && j >= 0 && (i as usize) < self.width && (j as usize) < self.height)
            .then(|| j as usize * self.width + i as usize)
    }

    /// The cell holding a map-frame point, if inside.
    pub fn index_of(&self, p: Vec2) -> Option<usize> {
        if !p.is_finite() {
            return None;
        }
        let i = (p.x / self.cell_m).floor() as i64 - i64::from(self.origin.i);
        let j = (p.y / self.cell_m).floor() as i64 - i64::from(self.origin.j);
        let fits = |v: i64| i32::try_from(v).ok();
        self.index(fits(i)?, fits(j)?)
    }

    /// The centre of cell `k`, map frame, m.
    pub fn center(&self, k: usize) -> Vec2 {
        let (i, j) = self.coords(k);
        Vec2::new(
            ((i + self.origin.i) as f32 + 0.5) * self.cell_m,
            ((j + self.origin.j) as f32 + 0.5) * self.cell_m,
        )
    }

    /// Whether every cell the segment passes through passes `ok` (an exact walk along the
    /// segment, cell by cell: a piece of a clear segment is clear too).
    pub fn segment_clear(&self, a: Vec2, b: Vec2, ok: impl Fn(usize) -> bool) -> bool {
        let local = |p: Vec2| {
            Vec2::new(
                p.x / self.cell_m - self.origin.i as f32,
                p.y / self.cell_m - self.origin.j as f32,
            )
        };
        let (a, b) = (local(a), local(b));
        let limit = (self.width + self.height) as f32;
        let inside = |p: Vec2| p.is_finite() && p.x.abs() < limit && p.y.abs() < limit;
        if !(inside(a) && inside(b)) {
            return false;
        }
        let (mut i, mut j) = (a.x.floor() as i32, a.y.floor() as i32);
        let end = (b.x.floor() as i32, b.y.floor() as i32);
        let d = b - a;
        // Along the segment (0..1): where the next column and row boundaries are crossed, and
        // how far apart the crossings are.
        let axis = |from: f32, cell: i32, delta: f32| -> (i32, f32, f32) {
            if delta > 0.0 {
                (1, (cell as f32 + 1.0 - from) / delta, 1.0 / delta)
            } else if delta < 0.0 {
                (-1, (from - cell as f32) / -delta, -1.0 / delta)
            } else {
                (0, f32::INFINITY, f32::INFINITY)
            }
        };
        let (si, mut next_x, step_x) = axis(a.x, i, d.x);
        let (sj, mut next_y, step_y) = axis(a.y, j, d.y);
        // Through a cell corner (within a thousandth of a cell) both cells beside the corner
        // count as touched: a piece of the segment, computed with other rounding, then checks
        // the same cells.
        let tie = 1e-3 / d.norm().max(1e-6);
        let cell_ok = |i: i32, j: i32| self.index(i, j).is_some_and(&ok);
        let steps = (end.0 - i).unsigned_abs() + (end.1 - j).unsigned_abs();
        for _ in 0..steps {
            if !cell_ok(i, j) {
                return false;
            }
            if (i, j) == end {
                break;
            }
            if (next_x - next_y).abs() < tie && si != 0 && sj != 0 {
                if !(cell_ok(i + si, j) && cell_ok(i, j + sj)) {
                    return false;
                }
                (i, j) = (i + si, j + sj);
                next_x += step_x;
                next_y += step_y;
            } else if next_x < next_y {
                i += si;
                next_x += step_x;
            } else {
                j += sj;
                next_y += step_y;
            }
        }
        self.index(i, j).is_some_and(&ok) && self.index(end.0, end.1).is_some_and(&ok)
    }
}

/// How far plans keep from mapped obstacles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    /// No planned cell comes closer, m.
    pub r_min_m: f32,
    /// Plans keep this much where the map has room, m (at least `r_min_m`).
    pub preferred_m: f32,
    /// Cost per metre of a step closer than the preferred clearance (at least 1).
    pub tight_cost: f32,
}

/// A planning cell's state so far merged with one more map cell's.
fn merge(a: CellState, b: CellState) -> CellState {
    match (a, b) {
        (CellState::Occupied, _) | (_, CellState::Occupied) => CellState::Occupied,
        (CellState::Free, _) | (_, CellState::Free) => CellState::Free,
        _ => CellState::Unknown,
    }
}

/// The planning-cell state of a block of map cells (used to check one cell without building
/// the whole grid).
pub fn block_state(grid: &OccupancyGrid, corner: Cell, factor: i32) -> CellState {
    let mut s = CellState::Unknown;
    for j in 0..factor {
        for i in 0..factor {
            s = merge(s, grid.state(Cell::new(corner.i + i, corner.j + j)));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// A free cell is unsafe exactly when its centre lies within `r_min` of an occupied
        /// cell's square, checked against every occupied cell, on random grids and radii.
        #[test]
        fn inflation_marks_every_centre_within_reach_of_an_occupied_square(
            cells in proptest::collection::vec(0u8..10, 1..400),
            width in 1usize..30,
            r_min_m in 0.0f32..0.6,
        ) {
            let height = cells.len().div_ceil(width);
            let states: Vec<CellState> = (0..width * height)
                .map(|k| match cells.get(k).copied().unwrap_or(0) {
                    0 => CellState::Occupied,
                    1 => CellState::Unknown,
                    _ => CellState::Free,
                })
                .collect();
            let cell_m = 0.1;
            let mut g = PlanGrid::from_states(Cell::new(-3, 2), width, height, cell_m, states)
                .unwrap();
            g.inflate(r_min_m);
            for k in 0..g.len() {
                let (i, j) = g.coords(k);
                let near = (0..g.len()).filter(|&o| g.state(o) == CellState::Occupied).any(|o| {
                    let (oi, oj) = g.coords(o);
                    let gap = |d: i32| ((d.abs() as f32) - 0.5).max(0.0) * cell_m;
                    gap(i - oi).hypot(gap(j - oj)) < r_min_m
                });
                let expected = g.state(k) == CellState::Free && !near;
                proptest::prop_assert_eq!(g.is_safe(k), expected, "cell {} {}", i, j);
            }
        }
    }
}
