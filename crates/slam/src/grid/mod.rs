//! The occupancy grid of the whole area (seed 002 Fig. 7, CoreSLAM's map): every keyframe's
//! beams at its optimised pose, rebuilt in one pass when loop closure moves the poses.
//!
//! Each cell counts the beams that ended in it (hits) and the beams that passed through it
//! (misses); its state is the hit ratio `hits / (hits + misses)` against two thresholds. Counts
//! rather than clamped log-odds because a rebuild then gives the same map whatever order the
//! keyframes come in, the state is the same frequency GMapping and map_server's thresholds
//! speak of, and an update is a 16-bit increment. Counts saturate by halving both, which keeps
//! the ratio.
//!
//! Bounds: the grid grows tile by tile as beams reach new area (memory follows the area
//! mapped), up to [`GridConfig::max_extent_m`] across and [`GridConfig::max_cells`] cells; a
//! scan that would go beyond either is refused whole with an error, and the grid is unchanged.

mod frame;
mod occupancy;
mod prepared;
mod raster;
mod raycast;
mod see_through;
mod tiles;

pub use frame::{Cell, CellRect, GridFrame};
pub use occupancy::OccupancyGrid;
pub use prepared::PreparedScan;
pub use raster::Raster;
pub use raycast::trace;
pub use tiles::TILE_BYTES;

/// A cell's state by the thresholds of [`GridConfig`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellState {
    Unknown,
    Free,
    Occupied,
}

/// Grid parameters; the defaults suit the indoor lidars of the project (XV-11, URG-04LX,
/// UTM-30LX) and a map of a building.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridConfig {
    /// Cell side, m. 5 cm: finer than the XV-11's range noise is wasted, coarser blurs doors.
    pub resolution_m: f32,
    /// Largest side of the mapped area, and farthest any point may lie from the map frame's
    /// origin, m. Bounds the tile index (a few hundred kB) and catches a diverged pose before
    /// it turns into a huge allocation.
    pub max_extent_m: f32,
    /// Most cells the grid may allocate (4 bytes each). 8 Mi cells is 32 MiB: 20,000 m² at 5 cm.
    pub max_cells: usize,
    /// A cell whose hit ratio is at least this is occupied (map_server's `occupied_thresh`).
    pub occupied_ratio: f32,
    /// A cell whose hit ratio is at most this is free (map_server's `free_thresh`).
    pub free_ratio: f32,
    /// An occupied cell with fewer hits than this fraction of the most-hit of its eight
    /// neighbours is shown unknown instead: range noise scatters a few hits just beyond a wall,
    /// where no beam passes to clear them, and they would thicken every wall by a cell or two
    /// on its far side. 0 turns the rule off.
    pub neighbour_hit_fraction: f32,
    /// Cells holding at least this many hits are a surface, and a beam that passes through
    /// one where the surface runs along the beam adds no miss to it (0: every beam clears
    /// every cell it passes; see `Tiles::add_misses_along`). Without it, the beams that pass a
    /// wall's end at a shallow angle wear away its last few decimetres (a door's jambs), the
    /// lidar returning nothing from the wall itself at that angle. The count is more than the
    /// one or two hits a cell gets from one keyframe of the XV-11 at a few metres, so a
    /// surface is one that several keyframes saw.
    pub solid_hits: u16,
    /// How far an invalid ("no return") beam clears free space, m; `None`: not at all (see
    /// [`PreparedScan::from_beams`] for why that is the default).
    pub no_return_clear_m: Option<f32>,
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.05,
            max_extent_m: 500.0,
            max_cells: 8 << 20,
            occupied_ratio: 0.65,
            free_ratio: 0.196,
            neighbour_hit_fraction: 0.25,
            solid_hits: 3,
            no_return_clear_m: None,
        }
    }
}

/// Cells along the extent may not exceed this: the tile index then stays under 8 MiB.
const MAX_EXTENT_CELLS: f32 = 65_536.0;

impl GridConfig {
    /// Checks every field; the error names the field and the valid range.
    pub fn validate(&self) -> Result<(), GridError> {
        let bad = |s: String| Err(GridError::Config(s));
        let r = self.resolution_m;
        if !(r.is_finite() && r >= 0.001) {
            return bad(format!("resolution_m {r} must be at least 0.001 m"));
        }
        let e = self.max_extent_m;
        if !(e.is_finite() && e >= r && e / r <= MAX_EXTENT_CELLS) {
            return bad(format!(
                "max_extent_m {e} must lie between resolution_m and {} cells ({} m at {r} m)",
                MAX_EXTENT_CELLS,
                MAX_EXTENT_CELLS * r
            ));
        }
        if self.max_cells == 0 {
            return bad("max_cells must be positive".into());
        }
        let (o, f) = (self.occupied_ratio, self.free_ratio);
        if !(0.0 <= f && f < o && o <= 1.0) {
            return bad(format!(
                "thresholds need 0 <= free_ratio < occupied_ratio <= 1, got {f} and {o}"
            ));
        }
        let n = self.neighbour_hit_fraction;
        if !(0.0..=1.0).contains(&n) {
            return bad(format!("neighbour_hit_fraction {n} must lie in 0..=1"));
        }
        if let Some(d) = self.no_return_clear_m {
            if !(d.is_finite() && d > 0.0) {
                return bad(format!("no_return_clear_m {d} must be finite and positive"));
            }
        }
        Ok(())
    }
}

/// Why a scan or a configuration was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum GridError {
    /// A configuration field or argument is out of range.
    Config(String),
    /// The pose has a NaN or infinite component.
    NonFinitePose,
    /// The map would be wider than [`GridConfig::max_extent_m`] or reach farther from its
    /// origin.
    TooWide {
        span_m: [f32; 2],
        farthest_m: f32,
        max_extent_m: f32,
    },
    /// The map would need more than [`GridConfig::max_cells`] cells.
    TooManyCells { needed: usize, max_cells: usize },
    /// The map would not fit a raster of `max_pixels` pixels (output images).
    RasterTooLarge {
        width: i64,
        height: i64,
        max_pixels: usize,
    },
    /// A rebuild stopped at this keyframe (0-based); the grid holds the keyframes before it.
    InKeyframe { index: usize, error: Box<GridError> },
}

impl core::fmt::Display for GridError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GridError::Config(s) => write!(f, "grid configuration: {s}"),
            GridError::NonFinitePose => write!(f, "scan refused: its pose is not finite"),
            GridError::TooWide {
                span_m,
                farthest_m,
                max_extent_m,
            } => write!(
                f,
                "scan refused: the map would span {:.1} m x {:.1} m and reach {:.1} m from its \
                 origin, beyond the maximum extent of {max_extent_m} m (a pose or range is \
                 probably wrong; otherwise raise max_extent_m)",
                span_m[0], span_m[1], farthest_m
            ),
            GridError::TooManyCells { needed, max_cells } => write!(
                f,
                "scan refused: the map would need up to {needed} cells, more than the limit of \
                 {max_cells} (use a coarser resolution or raise max_cells)"
            ),
            GridError::RasterTooLarge {
                width,
                height,
                max_pixels,
            } => write!(
                f,
                "the map is {width} x {height} cells, more than the {max_pixels} pixels an \
                 output image may have (use a coarser resolution)"
            ),
            GridError::InKeyframe { index, error } => write!(f, "keyframe {index}: {error}"),
        }
    }
}

impl std::error::Error for GridError {}
