//! The grid itself: scan insertion, rebuild from keyframes, cell states.

use super::frame::{Cell, CellRect, GridFrame};
use super::prepared::PreparedScan;
use super::tiles::{cell_at, Tiles, TILE};
use super::{CellState, GridConfig, GridError};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Beam;

/// An occupancy grid over the map frame (see the module documentation for the model).
#[derive(Clone)]
pub struct OccupancyGrid {
    config: GridConfig,
    frame: GridFrame,
    tiles: Tiles,
    /// Cells any beam reached; `None` before the first scan.
    bounds: Option<CellRect>,
    /// End cells of the scan being inserted (kept to reuse the allocation).
    ends: Vec<Cell>,
    scans: usize,
}

impl core::fmt::Debug for OccupancyGrid {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("OccupancyGrid")
            .field("config", &self.config)
            .field("bounds", &self.bounds)
            .field("scans", &self.scans)
            .field("tiles", &self.tiles.allocated())
            .finish()
    }
}

impl OccupancyGrid {
    pub fn new(config: GridConfig) -> Result<Self, GridError> {
        config.validate()?;
        Ok(Self {
            config,
            frame: GridFrame::new(config.resolution_m),
            tiles: Tiles::default(),
            bounds: None,
            ends: Vec::new(),
            scans: 0,
        })
    }

    pub fn config(&self) -> &GridConfig {
        &self.config
    }

    pub fn frame(&self) -> GridFrame {
        self.frame
    }

    /// The rectangle of cells any beam reached, `None` while the grid is empty.
    pub fn bounds(&self) -> Option<CellRect> {
        self.bounds
    }

    /// Scans inserted since the grid was created or cleared.
    pub fn scans(&self) -> usize {
        self.scans
    }

    /// Heap bytes held by the counts and their index.
    pub fn memory_bytes(&self) -> usize {
        self.tiles.memory_bytes()
    }

    /// Forgets every scan and frees the tiles.
    pub fn clear(&mut self) {
        self.tiles = Tiles::default();
        self.bounds = None;
        self.scans = 0;
    }

    /// Inserts a device scan at `pose` (the sensor's pose in the map frame): shorthand for
    /// [`PreparedScan::from_beams`] with this grid's no-return rule, then [`Self::insert`].
    pub fn insert_scan(
        &mut self,
        pose: Pose2,
        beams: &[Beam],
        max_range_m: f32,
    ) -> Result<(), GridError> {
        let scan = PreparedScan::from_beams(beams, max_range_m, self.config.no_return_clear_m)?;
        self.insert(pose, &scan)
    }

    /// Inserts a prepared scan at `pose`: every cell a beam passes through gains a miss, the
    /// cell a hit ends in gains a hit, the cell a clearing beam ends in a miss. A scan that
    /// would take the grid beyond its extent or cell budget is refused whole.
    pub fn insert(&mut self, pose: Pose2, scan: &PreparedScan) -> Result<(), GridError> {
        if !pose.is_finite() {
            return Err(GridError::NonFinitePose);
        }
        let origin = self.frame.cell_of(pose.translation());
        let (s, c) = (pose.theta.sin(), pose.theta.cos());
        let mut rect = CellRect::of(origin);
        let mut farthest = pose.x.abs().max(pose.y.abs());
        self.ends.clear();
        for p in scan.hits().iter().chain(scan.clears()) {
            let w = Vec2::new(c * p.x - s * p.y + pose.x, s * p.x + c * p.y + pose.y);
            farthest = farthest.max(w.x.abs()).max(w.y.abs());
            let cell = self.frame.cell_of(w);
            rect.include(cell);
            self.ends.push(cell);
        }
        let scan_rect = rect;
        let rect = self.bounds.map_or(rect, |b| b.union(rect));
        self.check_room(rect, scan_rect, farthest)?;
        self.tiles.cover(rect);
        let tiles = &mut self.tiles;
        let hits = scan.hits().len();
        for (k, &end) in self.ends.iter().enumerate() {
            tiles.add_misses_along(origin, end);
            if k < hits {
                tiles.add_hit(end);
            } else {
                tiles.add_miss(end);
            }
        }
        self.bounds = Some(rect);
        self.scans += 1;
        Ok(())
    }

    /// Refuses a scan that would widen the map (to `rect`) past the extent, or might need more
    /// tiles than the budget allows (counted over the unallocated tiles of the scan's own
    /// rectangle: an upper bound, so the refusal can come before any change).
    fn check_room(
        &self,
        rect: CellRect,
        scan_rect: CellRect,
        farthest_m: f32,
    ) -> Result<(), GridError> {
        let r = self.config.resolution_m;
        let span_m = [rect.width() as f32 * r, rect.height() as f32 * r];
        let max = self.config.max_extent_m;
        if farthest_m.is_nan() || farthest_m > max || span_m[0] > max || span_m[1] > max {
            return Err(GridError::TooWide {
                span_m,
                farthest_m,
                max_extent_m: max,
            });
        }
        let max_tiles = self.config.max_cells.div_ceil(TILE * TILE);
        let tiles = self.tiles.allocated() + self.tiles.missing_in(scan_rect);
        if tiles > max_tiles {
            let needed = tiles * TILE * TILE;
            return Err(GridError::TooManyCells {
                needed,
                max_cells: self.config.max_cells,
            });
        }
        Ok(())
    }

    /// Clears the grid and inserts every keyframe at its (new) pose. On an error the grid
    /// holds the keyframes before the one named.
    pub fn rebuild<'a>(
        &mut self,
        keyframes: impl IntoIterator<Item = (Pose2, &'a PreparedScan)>,
    ) -> Result<(), GridError> {
        self.clear();
        for (index, (pose, scan)) in keyframes.into_iter().enumerate() {
            self.insert(pose, scan).map_err(|e| GridError::InKeyframe {
                index,
                error: Box::new(e),
            })?;
        }
        Ok(())
    }

    /// Lets the beams of a scan at `pose` clear what a keyframe saw only in passing: every cell
    /// a beam of `scan` passes through (hits and clears alike, not the cell it ends in) gains a
    /// miss if it holds between one and `max_hits` hits. A person walking past leaves a hit or two per cell in the one keyframe
    /// that caught them, and the scans after it see through the spot; a wall gathers hits from
    /// every keyframe that faces it, so the beams that graze it do not wear it away, and cells
    /// no keyframe reached stay unknown. Nothing else changes: the grid does not grow and no
    /// hit is added.
    pub fn see_through(
        &mut self,
        pose: Pose2,
        scan: &PreparedScan,
        max_hits: u16,
    ) -> Result<(), GridError> {
        if !pose.is_finite() {
            return Err(GridError::NonFinitePose);
        }
        let origin = self.frame.cell_of(pose.translation());
        let (s, c) = (pose.theta.sin(), pose.theta.cos());
        for p in scan.hits().iter().chain(scan.clears()) {
            let w = Vec2::new(c * p.x - s * p.y + pose.x, s * p.x + c * p.y + pose.y);
            let tiles = &mut self.tiles;
            super::raycast::trace(origin, self.frame.cell_of(w), |cell| {
                let hits = tiles.counts(cell).0;
                if (1..=max_hits).contains(&hits) {
                    tiles.add_miss(cell);
                }
            });
        }
        Ok(())
    }

    /// (hits, misses) of a cell.
    pub fn counts(&self, cell: Cell) -> (u16, u16) {
        self.tiles.counts(cell)
    }

    pub fn state(&self, cell: Cell) -> CellState {
        let (h, m) = self.tiles.counts(cell);
        self.state_of(cell, h, m)
    }

    /// The state from a cell's counts, with the neighbour rule of
    /// [`GridConfig::neighbour_hit_fraction`]: only cells the ratio calls occupied look at
    /// their eight neighbours, so the rule costs little.
    fn state_of(&self, cell: Cell, h: u16, m: u16) -> CellState {
        let state = classify(&self.config, h, m);
        let fraction = self.config.neighbour_hit_fraction;
        if state != CellState::Occupied || fraction <= 0.0 {
            return state;
        }
        let mut most = 0;
        for dj in -1..=1 {
            for di in -1..=1 {
                let n = Cell::new(cell.i.saturating_add(di), cell.j.saturating_add(dj));
                most = most.max(self.tiles.counts(n).0);
            }
        }
        if f32::from(h) < fraction * f32::from(most) {
            CellState::Unknown
        } else {
            state
        }
    }

    /// The state of the cell holding a map-frame point.
    pub fn state_at(&self, p: Vec2) -> CellState {
        self.state(self.frame.cell_of(p))
    }

    /// Every occupied cell (in tile order).
    pub fn occupied_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.tiles.iter().flat_map(move |(corner, tile)| {
            (0..TILE * TILE)
                .map(move |k| (cell_at(corner, k), tile.hits[k], tile.misses[k]))
                .filter(move |&(c, h, m)| self.state_of(c, h, m) == CellState::Occupied)
                .map(|(c, _, _)| c)
        })
    }

    /// Allocated cells (a multiple of the tile size).
    pub fn allocated_cells(&self) -> usize {
        self.tiles.allocated() * TILE * TILE
    }
}

/// The state of a cell with `h` hits and `m` misses.
fn classify(config: &GridConfig, h: u16, m: u16) -> CellState {
    let n = f32::from(h) + f32::from(m);
    if n == 0.0 {
        CellState::Unknown
    } else if f32::from(h) >= config.occupied_ratio * n {
        CellState::Occupied
    } else if f32::from(h) <= config.free_ratio * n {
        CellState::Free
    } else {
        CellState::Unknown
    }
}
