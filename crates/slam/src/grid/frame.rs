//! Cell coordinates of the map frame: cell (i, j) covers `[i r, (i + 1) r) x [j r, (j + 1) r)`
//! metres for resolution `r`, so the map frame's origin is the lower-left corner of cell (0, 0)
//! and cells have signed indices. A grid that grows in every direction then never has to move
//! its contents or its origin, and rebuilding it at new poses keeps every cell where it was.

use plumbline_core::geom::Vec2;

/// A cell's column (x) and row (y), signed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Cell {
    pub i: i32,
    pub j: i32,
}

impl Cell {
    pub const fn new(i: i32, j: i32) -> Self {
        Self { i, j }
    }
}

/// An inclusive rectangle of cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellRect {
    pub min: Cell,
    pub max: Cell,
}

impl CellRect {
    /// The rectangle of one cell.
    pub fn of(c: Cell) -> Self {
        Self { min: c, max: c }
    }

    /// The smallest rectangle holding both.
    pub fn union(self, o: CellRect) -> CellRect {
        CellRect {
            min: Cell::new(self.min.i.min(o.min.i), self.min.j.min(o.min.j)),
            max: Cell::new(self.max.i.max(o.max.i), self.max.j.max(o.max.j)),
        }
    }

    pub fn include(&mut self, c: Cell) {
        *self = self.union(CellRect::of(c));
    }

    /// Columns, as i64 so that a rectangle spanning the whole i32 range does not overflow.
    pub fn width(&self) -> i64 {
        i64::from(self.max.i) - i64::from(self.min.i) + 1
    }

    pub fn height(&self) -> i64 {
        i64::from(self.max.j) - i64::from(self.min.j) + 1
    }
}

/// The map frame's metres-to-cells conversion at one resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFrame {
    resolution_m: f32,
    inv_resolution: f32,
}

impl GridFrame {
    /// `resolution_m` must be finite and positive (checked by the grid's configuration).
    pub fn new(resolution_m: f32) -> Self {
        Self {
            resolution_m,
            inv_resolution: 1.0 / resolution_m,
        }
    }

    pub fn resolution_m(&self) -> f32 {
        self.resolution_m
    }

    /// The cell holding a point. Floors without a libm call (the hot path of every beam); values
    /// beyond the i32 range saturate, and the grid's extent check then refuses them.
    pub fn cell_of(&self, p: Vec2) -> Cell {
        Cell::new(
            floor_i32(p.x * self.inv_resolution),
            floor_i32(p.y * self.inv_resolution),
        )
    }

    /// The centre of a cell, m.
    pub fn center(&self, c: Cell) -> Vec2 {
        Vec2::new(
            (c.i as f32 + 0.5) * self.resolution_m,
            (c.j as f32 + 0.5) * self.resolution_m,
        )
    }

    /// The lower-left corner of a cell in f64 (map files print it), m.
    pub fn corner_f64(&self, c: Cell) -> [f64; 2] {
        let r = f64::from(self.resolution_m);
        [f64::from(c.i) * r, f64::from(c.j) * r]
    }
}

fn floor_i32(v: f32) -> i32 {
    let t = v as i32;
    t.saturating_sub(i32::from((t as f32) > v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn cells_are_floored_on_both_sides_of_zero() {
        let f = GridFrame::new(0.05);
        assert_eq!(f.cell_of(Vec2::new(0.01, -0.01)), Cell::new(0, -1));
        assert_eq!(f.cell_of(Vec2::new(-0.051, 0.099)), Cell::new(-2, 1));
        assert_eq!(f.cell_of(Vec2::new(0.0, 0.0)), Cell::new(0, 0));
        assert_eq!(
            f.cell_of(Vec2::new(1e30, -1e30)),
            Cell::new(i32::MAX, i32::MIN)
        );
    }

    proptest! {
        #[test]
        fn a_point_lies_in_its_cell(x in -500.0f32..500.0, y in -500.0f32..500.0,
                                    r in prop::sample::select(vec![0.025f32, 0.05, 0.1, 0.2])) {
            let f = GridFrame::new(r);
            let c = f.cell_of(Vec2::new(x, y));
            let [cx, cy] = f.corner_f64(c);
            // One part in 1e6 of slack for the f32 product x / r near a cell border.
            let slack = 1e-6 * (1.0 + f64::from(x.abs().max(y.abs())) / f64::from(r));
            let (u, v) = ((f64::from(x) - cx) / f64::from(r), (f64::from(y) - cy) / f64::from(r));
            prop_assert!(u >= -slack && u < 1.0 + slack, "x {x} in cell {c:?}: {u}");
            prop_assert!(v >= -slack && v < 1.0 + slack, "y {y} in cell {c:?}: {v}");
        }

        #[test]
        fn a_cell_centre_maps_back_to_its_cell(i in -20000i32..20000, j in -20000i32..20000,
                                              r in prop::sample::select(vec![0.025f32, 0.05, 0.1])) {
            let f = GridFrame::new(r);
            prop_assert_eq!(f.cell_of(f.center(Cell::new(i, j))), Cell::new(i, j));
        }
    }
}
