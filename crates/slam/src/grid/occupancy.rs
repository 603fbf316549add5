//! The grid itself: scan insertion, rebuild from keyframes, cell states.

use super::frame::{Cell, CellRect, GridFrame};
use super::prepared::PreparedScan;
use super::see_through::Candidates;
use super::tiles::{cell_at, offset_in_tile, Tiles, TILE};
use super::{CellState, GridConfig, GridError};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Beam;

/// Most threads a map operation uses.
const MAX_THREADS: usize = 4;
/// Fewest scans worth a thread of their own.
const MIN_ITEMS_PER_THREAD: usize = 64;

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
    /// Cells along the beam being inserted that hold a surface (kept likewise).
    solid: Vec<(i64, Cell)>,
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
            solid: Vec::new(),
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
    /// cell a hit ends in gains a hit, the cell a clearing beam ends in a miss. The hits go in
    /// first, and a beam that runs along cells holding [`GridConfig::solid_hits`] hits does not
    /// count a miss in them (see [`Tiles::add_misses_along`]). A scan that would take the grid
    /// beyond its extent or cell budget is refused whole.
    pub fn insert(&mut self, pose: Pose2, scan: &PreparedScan) -> Result<(), GridError> {
        let origin = self.insert_hits(pose, scan, false)?;
        self.add_misses(origin, scan.hits().len());
        Ok(())
    }

    /// The cell of the sensor at `pose`, and the end cells of the scan's beams in
    /// `self.ends`, hits first; also the rectangle of those cells and the farthest coordinate
    /// any of them reaches from the origin, m.
    fn place(&mut self, pose: Pose2, scan: &PreparedScan) -> (Cell, CellRect, f32) {
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
        (origin, rect, farthest)
    }

    /// The first half of [`Self::insert`]: checks the room the scan needs, grows the grid to
    /// hold it, and adds its hits; returns the sensor's cell, with the beams' end cells left
    /// in `self.ends`. With `reserve_beams`, also allocates every tile the beams pass through,
    /// so that misses added after other scans' checks allocate nothing those checks did not
    /// allow (a rebuild); misses added at once allocate within this scan's own check.
    fn insert_hits(
        &mut self,
        pose: Pose2,
        scan: &PreparedScan,
        reserve_beams: bool,
    ) -> Result<Cell, GridError> {
        if !pose.is_finite() {
            return Err(GridError::NonFinitePose);
        }
        let (origin, scan_rect, farthest) = self.place(pose, scan);
        let rect = self.bounds.map_or(scan_rect, |b| b.union(scan_rect));
        self.check_room(rect, scan_rect, farthest)?;
        self.tiles.cover(rect);
        if reserve_beams {
            for &end in &self.ends {
                self.tiles.allocate_along(origin, end);
            }
        }
        for &end in &self.ends[..scan.hits().len()] {
            self.tiles.add_hit(end);
        }
        self.bounds = Some(rect);
        self.scans += 1;
        Ok(origin)
    }

    /// The misses along every beam of a scan whose hits [`Self::insert_hits`] took earlier,
    /// with its beams reserved (a rebuild adds all hits before any miss).
    fn insert_misses(&mut self, pose: Pose2, scan: &PreparedScan) {
        let (origin, _, _) = self.place(pose, scan);
        self.add_misses(origin, scan.hits().len());
    }

    /// The misses along the beams from `origin` to the end cells in `self.ends`, of which the
    /// first `hits` end in a hit.
    fn add_misses(&mut self, origin: Cell, hits: usize) {
        let solid_hits = self.config.solid_hits;
        for (k, &end) in self.ends.iter().enumerate() {
            self.tiles
                .add_misses_along(origin, end, k >= hits, solid_hits, &mut self.solid);
        }
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

    /// Clears the grid and inserts every keyframe at its (new) pose: every keyframe's hits
    /// first, then every keyframe's misses, so that which beams run along a surface (see
    /// [`Self::insert`]) is judged against all the hits, and the grid is the same whatever
    /// order the keyframes come in. On an error the grid holds the keyframes before the one
    /// named. A long list is inserted in halves on two threads when the result is sure to be
    /// the same (see [`Self::rebuilt_in_halves`]).
    pub fn rebuild<'a>(
        &mut self,
        keyframes: impl IntoIterator<Item = (Pose2, &'a PreparedScan)>,
    ) -> Result<(), GridError> {
        let keyframes: Vec<(Pose2, &PreparedScan)> = keyframes.into_iter().collect();
        self.clear();
        if let Some(grid) = self.rebuilt_in_halves(&keyframes) {
            *self = grid;
            return Ok(());
        }
        let mut refused = None;
        for (index, &(pose, scan)) in keyframes.iter().enumerate() {
            if let Err(e) = self.insert_hits(pose, scan, true) {
                refused = Some(GridError::InKeyframe {
                    index,
                    error: Box::new(e),
                });
                break;
            }
        }
        for &(pose, scan) in &keyframes[..self.scans] {
            self.insert_misses(pose, scan);
        }
        refused.map_or(Ok(()), Err)
    }

    /// The (cleared) grid with the keyframes inserted in halves on this thread and another,
    /// the counts then added: the hits of each half, then, on the sum of the hits, the misses
    /// of each half. `None`, to insert them one by one instead, unless that is sure to give
    /// the same grid: both halves went in whole, no count saturated in either or in a sum
    /// (counts are then order-free), and the merged map is within the extent and holds no
    /// more tiles than the budget (so no keyframe would have been refused). Also `None` on
    /// one core or for a short list.
    fn rebuilt_in_halves(&self, keyframes: &[(Pose2, &PreparedScan)]) -> Option<OccupancyGrid> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        if cores < 2 || keyframes.len() < 2 * MIN_ITEMS_PER_THREAD {
            return None;
        }
        let halves = keyframes.split_at(keyframes.len() / 2);
        let hits = |from: &OccupancyGrid, part: &[(Pose2, &PreparedScan)]| {
            let mut grid = from.clone();
            for &(pose, scan) in part {
                grid.insert_hits(pose, scan, true).ok()?;
            }
            Some(grid)
        };
        let (a, b) = in_two_threads(halves, |part| hits(self, part));
        let (mut grid, b) = (a?, b?);
        let rect = grid.bounds?.union(b.bounds?);
        let r = self.config.resolution_m;
        let span_m = (rect.width().max(rect.height()) as f32) * r;
        let max_tiles = self.config.max_cells.div_ceil(TILE * TILE);
        if span_m > self.config.max_extent_m || Tiles::tiles_in(rect) > max_tiles {
            return None;
        }
        grid.tiles.cover(rect);
        grid.tiles.add(&b.tiles, true).then_some(())?;
        grid.bounds = Some(rect);
        grid.scans += b.scans;
        let misses = |part: &[(Pose2, &PreparedScan)]| {
            let mut half = grid.clone();
            for &(pose, scan) in part {
                half.insert_misses(pose, scan);
            }
            half
        };
        let (mut a, b) = in_two_threads(halves, misses);
        a.tiles.add(&b.tiles, false).then_some(a)
    }

    /// Lets the beams of scans at their poses clear what a keyframe saw only in passing: every
    /// cell a beam passes through (hits and clears alike, not the cell it ends in) gains a miss
    /// if it holds between one and `max_hits` hits. A person walking past leaves a hit or two
    /// per cell in the one keyframe that caught them, and the scans after it see through the
    /// spot; a wall gathers hits from every keyframe that faces it, so the beams that graze it
    /// do not wear it away, and cells no keyframe reached stay unknown. Nothing else changes:
    /// the grid does not grow and no hit is added. A scan with a non-finite pose refuses the
    /// whole call, and the grid is unchanged.
    pub fn see_through<'a>(
        &mut self,
        scans: impl IntoIterator<Item = (Pose2, &'a PreparedScan)>,
        max_hits: u16,
    ) -> Result<(), GridError> {
        let scans: Vec<(Pose2, &PreparedScan)> = scans.into_iter().collect();
        if scans.iter().any(|(pose, _)| !pose.is_finite()) {
            return Err(GridError::NonFinitePose);
        }
        let Some(bounds) = self.bounds else {
            return Ok(());
        };
        let span = [
            (i64::from(bounds.min.i), i64::from(bounds.max.i)),
            (i64::from(bounds.min.j), i64::from(bounds.max.j)),
        ];
        let candidates = Candidates::find(&self.tiles, 1..=max_hits);
        let grid = (&self.tiles, self.frame, span);
        let misses = sum_in_threads(&scans, candidates.counters(), |chunk, misses| {
            for &(pose, scan) in chunk {
                candidates.count_scan(grid, pose, scan, misses);
            }
        });
        candidates.apply(&misses, &mut self.tiles);
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
        let most = self.tiles.most_hits_around(cell);
        if f32::from(h) < fraction * f32::from(most) {
            CellState::Unknown
        } else {
            state
        }
    }

    /// Appends the states of cells `i0..=i1` of row `j` to `out`, as [`Self::state`] gives
    /// them, looking each tile up once rather than once a cell.
    pub fn row_states(&self, j: i32, i0: i32, i1: i32, out: &mut Vec<CellState>) {
        let mut i = i0;
        while i <= i1 {
            let cell = Cell::new(i, j);
            // The cells of this row up to the tile's right edge (or `i1`).
            let end = (i | (TILE as i32 - 1)).min(i1);
            match self.tiles.tile_at(cell) {
                None => out.extend((i..=end).map(|_| CellState::Unknown)),
                Some(tile) => {
                    let row = offset_in_tile(Cell::new(0, j));
                    out.extend((i..=end).map(|i| {
                        let k = row + (i & (TILE as i32 - 1)) as usize;
                        self.state_of(Cell::new(i, j), tile.cells[k].hits, tile.cells[k].misses)
                    }));
                }
            }
            i = end + 1;
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
                .map(move |k| (cell_at(corner, k), tile.cells[k].hits, tile.cells[k].misses))
                .filter(move |&(c, h, m)| self.state_of(c, h, m) == CellState::Occupied)
                .map(|(c, _, _)| c)
        })
    }

    /// Allocated cells (a multiple of the tile size).
    pub fn allocated_cells(&self) -> usize {
        self.tiles.allocated() * TILE * TILE
    }
}

/// `f` of each of a pair, the first on this thread and the second on another.
fn in_two_threads<T: Send, R: Send>((first, second): (T, T), f: impl Fn(T) -> R + Sync) -> (R, R) {
    std::thread::scope(|s| {
        let other = s.spawn(|| f(second));
        let a = f(first);
        (
            a,
            other
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e)),
        )
    })
}

/// Splits `items` among the available cores (at most [`MAX_THREADS`], and only when there are
/// enough to be worth a thread), lets `count` add into a copy of `zero` for each share, and
/// returns the sum: the same as one pass over all items, whatever the number of threads.
fn sum_in_threads<T: Sync>(
    items: &[T],
    zero: Vec<u64>,
    count: impl Fn(&[T], &mut [u64]) + Sync,
) -> Vec<u64> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = cores
        .min(MAX_THREADS)
        .min(items.len() / MIN_ITEMS_PER_THREAD)
        .max(1);
    let mut total = zero;
    if threads == 1 {
        count(items, &mut total);
        return total;
    }
    let share = items.len().div_ceil(threads);
    let (first, rest) = items.split_at(share);
    std::thread::scope(|s| {
        let others: Vec<_> = rest
            .chunks(share)
            .map(|chunk| {
                let (count, mut sums) = (&count, vec![0; total.len()]);
                s.spawn(move || {
                    count(chunk, &mut sums);
                    sums
                })
            })
            .collect();
        count(first, &mut total);
        for other in others {
            // A thread that panicked would have panicked on this one too: pass it on.
            let sums = other
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e));
            for (t, s) in total.iter_mut().zip(sums) {
                *t += s;
            }
        }
    });
    total
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
