//! Integer ray casting between two cells (Bresenham's line, as CoreSLAM and Hector mapping use
//! it): one add and one compare per cell and no floating point, which is what lets a whole map
//! be rebuilt from its keyframes in tens of milliseconds. The line is 8-connected: it visits one
//! cell per step along the major axis, the cell the straight line between the two cell centres
//! crosses there. A 4-connected traversal would touch up to twice as many cells and, near walls
//! seen at a grazing angle, mark more wall cells free.

use super::frame::Cell;

/// Bresenham's stepping for one line: it advances `major_step` every step and, when the
/// decision variable says the ideal line has passed half a cell, `minor_step` too.
#[derive(Clone, Copy, Debug)]
pub(super) struct Line {
    /// Steps (cells after the first) along the major axis.
    pub major: i64,
    pub minor: i64,
    pub major_step: (i32, i32),
    pub minor_step: (i32, i32),
}

impl Line {
    #[inline]
    pub fn new(from: Cell, to: Cell) -> Line {
        let dx = i64::from(to.i) - i64::from(from.i);
        let dy = i64::from(to.j) - i64::from(from.j);
        let (sx, sy) = (dx.signum() as i32, dy.signum() as i32);
        if dx.abs() >= dy.abs() {
            Line {
                major: dx.abs(),
                minor: dy.abs(),
                major_step: (sx, 0),
                minor_step: (0, sy),
            }
        } else {
            Line {
                major: dy.abs(),
                minor: dx.abs(),
                major_step: (0, sy),
                minor_step: (sx, 0),
            }
        }
    }

    /// The decision variable before the first step: twice the minor-axis offset from the
    /// ideal line, scaled by the major length, less half a cell.
    pub fn first_err(&self) -> i64 {
        2 * self.minor - self.major
    }
}

/// Calls `visit` for every cell on the line from `from` up to, but not including, `to`: the
/// cells a beam passes through before the cell it ends in. Each cell is visited once, in order.
#[inline]
pub fn trace(from: Cell, to: Cell, mut visit: impl FnMut(Cell)) {
    let line = Line::new(from, to);
    let (mut i, mut j) = (from.i, from.j);
    let mut err = line.first_err();
    for _ in 0..line.major {
        visit(Cell::new(i, j));
        if err > 0 {
            i += line.minor_step.0;
            j += line.minor_step.1;
            err -= 2 * line.major;
        }
        i += line.major_step.0;
        j += line.major_step.1;
        err += 2 * line.minor;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashSet;

    fn line(a: Cell, b: Cell) -> Vec<Cell> {
        let mut v = Vec::new();
        trace(a, b, |c| v.push(c));
        v.push(b);
        v
    }

    #[test]
    fn horizontal_diagonal_and_steep_lines() {
        let c = Cell::new;
        assert_eq!(line(c(0, 0), c(3, 0)), [c(0, 0), c(1, 0), c(2, 0), c(3, 0)]);
        assert_eq!(line(c(0, 0), c(-2, -2)), [c(0, 0), c(-1, -1), c(-2, -2)]);
        assert_eq!(line(c(5, 5), c(6, 8)), [c(5, 5), c(5, 6), c(6, 7), c(6, 8)]);
        assert_eq!(line(c(1, 1), c(1, 1)), [c(1, 1)]);
    }

    proptest! {
        /// Every cell of the line is visited exactly once, the line is 8-connected and advances
        /// one cell a step along the major axis, it starts at the sensor's cell and ends in the
        /// beam's end cell, and each cell is the one the ideal line crosses in its column (row).
        #[test]
        fn each_cell_on_the_line_once_ending_in_the_end_cell(
            ai in -300i32..300, aj in -300i32..300, bi in -300i32..300, bj in -300i32..300,
        ) {
            let (a, b) = (Cell::new(ai, aj), Cell::new(bi, bj));
            let cells = line(a, b);
            let (dx, dy) = (bi - ai, bj - aj);
            prop_assert_eq!(cells.len() as i32, dx.abs().max(dy.abs()) + 1);
            prop_assert_eq!(cells[0], a);
            prop_assert_eq!(*cells.last().unwrap(), b);
            let unique: HashSet<Cell> = cells.iter().copied().collect();
            prop_assert_eq!(unique.len(), cells.len());
            for w in cells.windows(2) {
                let (di, dj) = (w[1].i - w[0].i, w[1].j - w[0].j);
                prop_assert!(di.abs() <= 1 && dj.abs() <= 1 && (di, dj) != (0, 0));
                if dx.abs() >= dy.abs() { prop_assert_eq!(di, dx.signum()); }
                else { prop_assert_eq!(dj, dy.signum()); }
            }
            for c in &cells {
                // Offset along the minor axis from the ideal line through the two centres.
                let off = if dx == 0 && dy == 0 {
                    0.0
                } else if dx.abs() >= dy.abs() {
                    let ideal = f64::from(aj) + f64::from(c.i - ai) * f64::from(dy) / f64::from(dx);
                    (f64::from(c.j) - ideal).abs()
                } else {
                    let ideal = f64::from(ai) + f64::from(c.j - aj) * f64::from(dx) / f64::from(dy);
                    (f64::from(c.i) - ideal).abs()
                };
                prop_assert!(off <= 0.5 + 1e-12, "cell {c:?} is {off} cells off the line");
            }
        }
    }
}
