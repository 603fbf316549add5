//! The local map: a rolling grid of cells, each holding the running point statistics of the
//! walls seen in it, so a cell answers "which line passes here" in O(1).
//!
//! Why statistics and not points: the map then costs a fixed few bytes per cell whatever the
//! number of scans, averages the range noise of every scan that saw a wall, and fits a line per
//! cell the way the normal-distributions transform does (Biber & Straßer 2003), which the
//! point-to-line residual needs. Why rolling: the cell of world index (ix, iy) lives in slot
//! (ix mod side, iy mod side) and remembers its index, so the vehicle can travel any distance
//! over a caller buffer of fixed size; what it left far behind is simply overwritten.

use crate::geom::Vec2;
use crate::matching::linalg::sym2_eigen;

/// One cell: point sums relative to the cell centre, so `f32` keeps millimetres far from the
/// origin, and the line fitted to them, refitted on every insert because lookups outnumber
/// inserts by the matcher's iteration count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapCell {
    index: [i16; 2],
    mean_stamp: f32,
    weight: f32,
    sx: f32,
    sy: f32,
    sxx: f32,
    sxy: f32,
    syy: f32,
    line: Option<CellLine>,
}

/// The wall a cell has seen: a point on it, its unit normal and the spread across it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellLine {
    pub mean: Vec2,
    pub normal: Vec2,
    /// Variance of the cell's points across the line, m².
    pub across_variance_m2: f32,
    /// Mean stamp of the cell's points (the caller's clock, e.g. a keyframe count), faded like
    /// the points: walls mapped long ago and left alone since stay old even after a few new
    /// points land on them, while walls seen again at every keyframe stay young.
    pub mean_stamp: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineMapConfig {
    /// Cell edge, m. Large enough to hold a stretch of wall worth fitting, small enough that a
    /// corner rarely shares a cell with a long wall.
    pub cell_m: f32,
    /// Weight at which a cell starts forgetting: older points fade so that a wall seen again
    /// after the pose was corrected does not stay smeared over its old place.
    pub max_weight: f32,
    /// Fewest points a cell needs before its line is used.
    pub min_points: f32,
    /// Largest across/along variance ratio of a usable cell (corners and clutter fail it).
    pub max_flatness: f32,
    /// Largest spread across the line of a usable cell, m.
    pub max_across_m: f32,
}

impl Default for LineMapConfig {
    fn default() -> Self {
        Self {
            cell_m: 0.25,
            max_weight: 40.0,
            min_points: 4.0,
            max_flatness: 0.05,
            max_across_m: 0.05,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineMapError {
    /// The buffer must be a non-empty square of `side * side` cells.
    NotSquare { cells: usize },
    /// The cell edge must be positive and finite.
    BadCellSize,
}

/// A local map over a caller-provided buffer of `side * side` cells.
#[derive(Debug)]
pub struct LineMap<'a> {
    cells: &'a mut [MapCell],
    side: usize,
    config: LineMapConfig,
}

impl<'a> LineMap<'a> {
    /// Empties `cells` and lays the map over it; `cells.len()` must be a perfect square.
    pub fn new(cells: &'a mut [MapCell], config: LineMapConfig) -> Result<Self, LineMapError> {
        let side = integer_sqrt(cells.len());
        if side == 0 || side * side != cells.len() {
            return Err(LineMapError::NotSquare { cells: cells.len() });
        }
        if !(config.cell_m.is_finite() && config.cell_m > 0.0) {
            return Err(LineMapError::BadCellSize);
        }
        cells.fill(MapCell::default());
        Ok(Self {
            cells,
            side,
            config,
        })
    }

    pub fn config(&self) -> &LineMapConfig {
        &self.config
    }

    /// Width of the square the map covers at once, m.
    pub fn extent_m(&self) -> f32 {
        self.side as f32 * self.config.cell_m
    }

    /// Adds one wall point (world frame) at time `stamp`. Points outside the representable range
    /// are ignored.
    pub fn insert(&mut self, p: Vec2, stamp: u32) {
        let Some(index) = self.index_of(p) else {
            return;
        };
        let centre = self.centre(index);
        let max_weight = self.config.max_weight;
        let slot = self.slot(index);
        let cell = &mut self.cells[slot];
        if cell.index != index || cell.weight <= 0.0 {
            *cell = MapCell {
                index,
                ..MapCell::default()
            };
        }
        if cell.weight + 1.0 > max_weight {
            let keep = (max_weight - 1.0).max(0.0) / cell.weight;
            cell.weight *= keep;
            cell.sx *= keep;
            cell.sy *= keep;
            cell.sxx *= keep;
            cell.sxy *= keep;
            cell.syy *= keep;
        }
        let d = p - centre;
        cell.mean_stamp += (stamp as f32 - cell.mean_stamp) / (cell.weight + 1.0);
        cell.weight += 1.0;
        cell.sx += d.x;
        cell.sy += d.y;
        cell.sxx += d.x * d.x;
        cell.sxy += d.x * d.y;
        cell.syy += d.y * d.y;
        cell.line = fit_line(cell, centre, &self.config);
    }

    /// The line of the cell holding `p` and of its three neighbours nearest to `p` (the 2x2
    /// block of cells whose centres surround `p`), so a wall on a cell border is still found.
    pub fn lines_near(&self, p: Vec2) -> [Option<CellLine>; 4] {
        let mut out = [None; 4];
        let Some(index) = self.index_of(p) else {
            return out;
        };
        let centre = self.centre(index);
        let step = |d: f32| if d >= 0.0 { 1 } else { -1 };
        let (dx, dy) = (step(p.x - centre.x), step(p.y - centre.y));
        for (k, (ox, oy)) in [(0, 0), (dx, 0), (0, dy), (dx, dy)].into_iter().enumerate() {
            let i = [index[0].saturating_add(ox), index[1].saturating_add(oy)];
            out[k] = self.line(i);
        }
        out
    }

    /// Cells with at least the minimum number of points (for reports and tests).
    pub fn occupied_cells(&self) -> usize {
        self.cells
            .iter()
            .filter(|c| c.weight >= self.config.min_points)
            .count()
    }

    fn line(&self, index: [i16; 2]) -> Option<CellLine> {
        let cell = &self.cells[self.slot(index)];
        if cell.index != index {
            return None;
        }
        cell.line
    }

    fn index_of(&self, p: Vec2) -> Option<[i16; 2]> {
        let f = |v: f32| {
            let i = libm::floorf(v / self.config.cell_m);
            // Keep one index of headroom so a neighbour lookup never wraps.
            (i.abs() < (i16::MAX - 1) as f32).then_some(i as i16)
        };
        Some([f(p.x)?, f(p.y)?])
    }

    fn centre(&self, index: [i16; 2]) -> Vec2 {
        let c = self.config.cell_m;
        Vec2::new((index[0] as f32 + 0.5) * c, (index[1] as f32 + 0.5) * c)
    }

    fn slot(&self, index: [i16; 2]) -> usize {
        let wrap = |i: i16| (i as i32).rem_euclid(self.side as i32) as usize;
        wrap(index[1]) * self.side + wrap(index[0])
    }
}

/// The cell's wall, if its points lie along one well enough to match against.
fn fit_line(cell: &MapCell, centre: Vec2, config: &LineMapConfig) -> Option<CellLine> {
    if cell.weight < config.min_points {
        return None;
    }
    let inv = 1.0 / cell.weight;
    let (mx, my) = (cell.sx * inv, cell.sy * inv);
    let cxx = cell.sxx * inv - mx * mx;
    let cxy = cell.sxy * inv - mx * my;
    let cyy = cell.syy * inv - my * my;
    let (hi, lo, normal) = sym2_eigen(cxx, cxy, cyy);
    let lo = lo.max(0.0);
    let max_across = config.max_across_m;
    if !(hi > 0.0 && lo <= config.max_flatness * hi && lo <= max_across * max_across) {
        return None;
    }
    Some(CellLine {
        mean: centre + Vec2::new(mx, my),
        normal,
        across_variance_m2: lo,
        mean_stamp: cell.mean_stamp,
    })
}

fn integer_sqrt(n: usize) -> usize {
    let mut r = libm::sqrt(n as f64) as usize;
    while r * r > n {
        r -= 1;
    }
    while (r + 1) * (r + 1) <= n {
        r += 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn wall(map: &mut LineMap, from: Vec2, to: Vec2, n: usize) {
        for k in 0..n {
            let t = k as f32 / (n - 1) as f32;
            map.insert(from + (to - from) * t, 0);
        }
    }

    #[test]
    fn buffer_must_be_square() {
        let mut cells = [MapCell::default(); 12];
        assert_eq!(
            LineMap::new(&mut cells, LineMapConfig::default()).unwrap_err(),
            LineMapError::NotSquare { cells: 12 }
        );
        let mut none: [MapCell; 0] = [];
        assert!(LineMap::new(&mut none, LineMapConfig::default()).is_err());
        let mut cells = [MapCell::default(); 16];
        let bad = LineMapConfig {
            cell_m: f32::NAN,
            ..LineMapConfig::default()
        };
        assert_eq!(
            LineMap::new(&mut cells, bad).unwrap_err(),
            LineMapError::BadCellSize
        );
    }

    #[test]
    fn a_wall_gives_its_line_in_every_cell_it_crosses() {
        let mut cells = [MapCell::default(); 64 * 64];
        let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
        // y = 0.5 x + 1, from x = -2 to 2.
        wall(&mut map, Vec2::new(-2.0, 0.0), Vec2::new(2.0, 2.0), 200);
        let expected_normal = Vec2::new(-0.5, 1.0) * (1.0 / libm::sqrtf(1.25));
        let mut found = 0;
        for k in 0..9 {
            let x = -1.6 + 0.4 * k as f32;
            let p = Vec2::new(x, 0.5 * x + 1.0);
            for line in map.lines_near(p).into_iter().flatten() {
                found += 1;
                assert!(line.normal.dot(expected_normal).abs() > 0.999);
                let off = (line.mean - p).dot(expected_normal);
                assert!(
                    off.abs() < 1e-3,
                    "mean {:?} off the wall by {off}",
                    line.mean
                );
            }
        }
        assert!(found >= 9, "{found}");
    }

    #[test]
    fn a_corner_cell_offers_no_line() {
        let mut cells = [MapCell::default(); 16 * 16];
        let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
        // An L inside the single cell [0, 0.25)².
        wall(&mut map, Vec2::new(0.01, 0.01), Vec2::new(0.24, 0.01), 10);
        wall(&mut map, Vec2::new(0.01, 0.01), Vec2::new(0.01, 0.24), 10);
        assert_eq!(map.lines_near(Vec2::new(0.1, 0.1))[0], None);
    }

    #[test]
    fn far_travel_overwrites_the_slot_instead_of_mixing_walls() {
        let mut cells = [MapCell::default(); 8 * 8];
        let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
        let span = map.extent_m();
        wall(&mut map, Vec2::new(0.0, 0.1), Vec2::new(0.24, 0.1), 20);
        // Same slot, one map width away, a wall across the other way.
        wall(
            &mut map,
            Vec2::new(span + 0.1, 0.0),
            Vec2::new(span + 0.1, 0.24),
            20,
        );
        assert_eq!(map.lines_near(Vec2::new(0.1, 0.1))[0], None);
        let line = map.lines_near(Vec2::new(span + 0.1, 0.1))[0].unwrap();
        assert!(line.normal.x.abs() > 0.999);
    }

    #[test]
    fn a_moved_wall_takes_over_once_the_old_points_fade() {
        let config = LineMapConfig::default();
        let mut cells = [MapCell::default(); 16 * 16];
        let mut map = LineMap::new(&mut cells, config).unwrap();
        for _ in 0..10 {
            wall(&mut map, Vec2::new(0.0, 0.10), Vec2::new(0.24, 0.10), 20);
        }
        for _ in 0..40 {
            wall(&mut map, Vec2::new(0.0, 0.14), Vec2::new(0.24, 0.14), 20);
        }
        let line = map.lines_near(Vec2::new(0.1, 0.12))[0].unwrap();
        assert!((line.mean.y - 0.14).abs() < 0.005, "{:?}", line.mean);
    }

    #[test]
    fn a_wall_seen_again_and_again_stays_young_and_a_wall_left_behind_stays_old() {
        let mut cells = [MapCell::default(); 16 * 16];
        let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
        let seen = |map: &mut LineMap, y: f32, stamp: u32| {
            for k in 0..10 {
                map.insert(Vec2::new(0.02 + 0.02 * k as f32, y), stamp);
            }
        };
        for stamp in 0..20 {
            seen(&mut map, 0.1, stamp);
            if stamp < 4 {
                seen(&mut map, 0.6, stamp);
            }
        }
        // One keyframe touches the old wall again at stamp 19.
        seen(&mut map, 0.6, 19);
        let young = map.lines_near(Vec2::new(0.1, 0.1))[0].unwrap();
        let old = map.lines_near(Vec2::new(0.1, 0.6))[0].unwrap();
        assert!(young.mean_stamp > 15.0, "{young:?}");
        assert!(old.mean_stamp < 10.0, "{old:?}");
    }

    proptest! {
        #[test]
        fn lookups_never_panic(x in -1.0e6f32..1.0e6, y in -1.0e6f32..1.0e6) {
            let mut cells = [MapCell::default(); 4 * 4];
            let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
            map.insert(Vec2::new(x, y), 0);
            let _ = map.lines_near(Vec2::new(x, y));
            let _ = map.lines_near(Vec2::new(f32::NAN, y));
            map.insert(Vec2::new(f32::INFINITY, y), 0);
        }

        #[test]
        fn isqrt_is_exact(n in 0usize..10_000_000) {
            let r = integer_sqrt(n);
            prop_assert!(r * r <= n && (r + 1) * (r + 1) > n);
        }
    }
}
