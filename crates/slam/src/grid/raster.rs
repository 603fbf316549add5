//! The grid as an image: one pixel per cell over the mapped bounds, row 0 at the top (largest
//! y), the layout of map_server's PGM and of a PNG. Every output is written from one raster, so
//! the PGM, the PNG and the path drawn on it are aligned pixel for pixel.

use super::frame::{Cell, CellRect, GridFrame};
use super::occupancy::OccupancyGrid;
use super::{CellState, GridError};
use plumbline_core::geom::Vec2;

/// Cell states over a rectangle of the map, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    pub width: usize,
    pub height: usize,
    frame: GridFrame,
    /// Cell of the bottom-left pixel.
    corner: Cell,
    pub states: Vec<CellState>,
}

impl Raster {
    /// Output images may have at most this many pixels (an RGB PNG of 32 M pixels is 96 MB of
    /// memory before compression).
    pub const MAX_PIXELS: usize = 32 << 20;

    /// The grid's mapped bounds as a raster; `None` for an empty grid.
    pub fn from_grid(grid: &OccupancyGrid) -> Result<Option<Raster>, GridError> {
        let Some(rect) = grid.bounds() else {
            return Ok(None);
        };
        let (w, h) = (rect.width(), rect.height());
        if w.saturating_mul(h) > Self::MAX_PIXELS as i64 {
            return Err(GridError::RasterTooLarge {
                width: w,
                height: h,
                max_pixels: Self::MAX_PIXELS,
            });
        }
        let (width, height) = (w as usize, h as usize);
        let mut states = Vec::with_capacity(width * height);
        for row in 0..height {
            let j = rect.max.j - row as i32;
            grid.row_states(j, rect.min.i, rect.max.i, &mut states);
        }
        Ok(Some(Raster {
            width,
            height,
            frame: grid.frame(),
            corner: rect.min,
            states,
        }))
    }

    pub fn resolution_m(&self) -> f32 {
        self.frame.resolution_m()
    }

    /// Map-frame position of the bottom-left pixel's lower-left corner (map_server's `origin`).
    pub fn origin_m(&self) -> [f64; 2] {
        self.frame.corner_f64(self.corner)
    }

    /// The cells this raster shows.
    pub fn rect(&self) -> CellRect {
        CellRect {
            min: self.corner,
            max: Cell::new(
                self.corner.i + self.width as i32 - 1,
                self.corner.j + self.height as i32 - 1,
            ),
        }
    }

    /// (column, row) of the pixel showing `cell`, `None` outside the raster.
    pub fn pixel_of_cell(&self, cell: Cell) -> Option<(usize, usize)> {
        let col = i64::from(cell.i) - i64::from(self.corner.i);
        let up = i64::from(cell.j) - i64::from(self.corner.j);
        ((0..self.width as i64).contains(&col) && (0..self.height as i64).contains(&up))
            .then(|| (col as usize, self.height - 1 - up as usize))
    }

    /// (column, row) of the pixel holding a map-frame point, as signed numbers so that a path
    /// leaving the raster can still be drawn up to its edge.
    pub fn pixel_of(&self, p: Vec2) -> (i64, i64) {
        let c = self.frame.cell_of(p);
        (
            i64::from(c.i) - i64::from(self.corner.i),
            self.height as i64 - 1 - (i64::from(c.j) - i64::from(self.corner.j)),
        )
    }

    /// The cell a pixel shows.
    pub fn cell_of_pixel(&self, col: usize, row: usize) -> Cell {
        Cell::new(
            self.corner.i + col as i32,
            self.corner.j + (self.height - 1 - row) as i32,
        )
    }

    pub fn state(&self, col: usize, row: usize) -> CellState {
        self.states[row * self.width + col]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridConfig, PreparedScan};
    use plumbline_core::geom::Pose2;
    use proptest::prelude::*;

    fn grid_with_hit(at: Vec2) -> OccupancyGrid {
        let mut g = OccupancyGrid::new(GridConfig::default()).unwrap();
        let mut s = PreparedScan::new();
        s.push_hit(at);
        g.insert(Pose2::new(0.0, 0.0, 0.0), &s).unwrap();
        g
    }

    #[test]
    fn top_row_is_the_largest_y_and_the_origin_is_the_bottom_left_corner() {
        let g = grid_with_hit(Vec2::new(0.52, 0.31));
        let r = Raster::from_grid(&g).unwrap().unwrap();
        assert_eq!((r.width, r.height), (11, 7));
        assert_eq!(r.origin_m(), [0.0, 0.0]);
        // The hit is in the top-right pixel, the sensor's cell bottom-left is free.
        assert_eq!(r.state(10, 0), CellState::Occupied);
        assert_eq!(r.state(0, 6), CellState::Free);
        assert_eq!(r.pixel_of(Vec2::new(0.52, 0.31)), (10, 0));
        let empty = OccupancyGrid::new(GridConfig::default()).unwrap();
        assert_eq!(Raster::from_grid(&empty).unwrap(), None);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Every pixel shows the state the grid gives its cell, over maps of several tiles with
        /// unallocated tiles between the ones beams reached.
        #[test]
        fn every_pixel_shows_its_cells_state(
            scans in prop::collection::vec(
                ((-6.0f32..6.0, -6.0f32..6.0), prop::collection::vec((-4.0f32..4.0, -4.0f32..4.0), 1..30)),
                1..6,
            ),
        ) {
            let mut g = OccupancyGrid::new(GridConfig::default()).unwrap();
            for ((x, y), hits) in &scans {
                let mut s = PreparedScan::new();
                for &(u, v) in hits {
                    s.push_hit(Vec2::new(u, v));
                }
                g.insert(Pose2::new(*x, *y, 0.0), &s).unwrap();
            }
            let r = Raster::from_grid(&g).unwrap().unwrap();
            for row in 0..r.height {
                for col in 0..r.width {
                    prop_assert_eq!(r.state(col, row), g.state(r.cell_of_pixel(col, row)));
                }
            }
        }
    }

    proptest! {
        /// A pixel's centre, placed with map_server's rule (origin + (col + 0.5, rows - row -
        /// 0.5) resolution), is the centre of the cell the raster shows there, and the pixel of
        /// that point is the pixel again.
        #[test]
        fn pixels_and_cells_agree_with_map_servers_rule(
            x in -40.0f32..40.0, y in -40.0f32..40.0, col in 0usize..50, row in 0usize..50,
        ) {
            let g = grid_with_hit(Vec2::new(x, y));
            let mut g2 = g.clone();
            let mut s = PreparedScan::new();
            s.push_hit(Vec2::new(x + 2.6, y - 2.6));
            g2.insert(Pose2::new(0.0, 0.0, 0.0), &s).unwrap();
            let r = Raster::from_grid(&g2).unwrap().unwrap();
            let (col, row) = (col % r.width, row % r.height);
            let o = r.origin_m();
            let res = f64::from(r.resolution_m());
            let px = o[0] + (col as f64 + 0.5) * res;
            let py = o[1] + ((r.height - row) as f64 - 0.5) * res;
            let c = r.cell_of_pixel(col, row);
            let centre = g.frame().center(c);
            prop_assert!((f64::from(centre.x) - px).abs() < 1e-4 && (f64::from(centre.y) - py).abs() < 1e-4);
            prop_assert_eq!(r.pixel_of_cell(c), Some((col, row)));
            prop_assert_eq!(r.pixel_of(centre), (col as i64, row as i64));
        }
    }
}
