//! Hit and miss counts stored in square tiles that are allocated when a beam first reaches
//! them, so memory follows the area mapped rather than its bounding box (an L-shaped building
//! or a long diagonal corridor costs its own area). The tiles hang off a dense index over the
//! tile bounding box: one pointer per 64 x 64 cells, which keeps a cell lookup to two loads.

use super::frame::{Cell, CellRect};
use super::raycast::Line;

/// Tiles are `TILE` x `TILE` cells.
pub const TILE_SHIFT: u32 = 6;
pub const TILE: usize = 1 << TILE_SHIFT;
const TILE_MASK: i32 = TILE as i32 - 1;
const TILE_CELLS: usize = TILE * TILE;

/// One cell's counts, side by side: the walk along a beam reads a cell's hits (the surface
/// rule) in the same step as it adds the miss, so keeping both in one 4-byte word makes that
/// step touch one cache line rather than two.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub hits: u16,
    pub misses: u16,
}

impl Counts {
    /// Counts saturate by halving both, which keeps their ratio (the cell's state) intact.
    fn halve(&mut self) {
        self.hits /= 2;
        self.misses /= 2;
    }
}

/// One tile's counts, row by row (cell `(i, j)` of the tile at `j * TILE + i`).
#[derive(Clone)]
pub struct Tile {
    pub cells: [Counts; TILE_CELLS],
}

impl Tile {
    fn new() -> Box<Tile> {
        Box::new(Tile {
            cells: [Counts::default(); TILE_CELLS],
        })
    }
}

/// Bytes of one allocated tile.
pub const TILE_BYTES: usize = core::mem::size_of::<Tile>();

/// The tiles and their index.
#[derive(Clone, Default)]
pub struct Tiles {
    /// Tile coordinates of index slot 0.
    ti0: i32,
    tj0: i32,
    /// Index size in tiles.
    tw: usize,
    th: usize,
    slots: Vec<Option<Box<Tile>>>,
    allocated: usize,
    /// Whether any count has saturated (and been halved) since the tiles were created.
    saturated: bool,
}

fn tile_of(c: Cell) -> (i32, i32) {
    (c.i >> TILE_SHIFT, c.j >> TILE_SHIFT)
}

pub fn offset_in_tile(c: Cell) -> usize {
    (((c.j & TILE_MASK) as usize) << TILE_SHIFT) | (c.i & TILE_MASK) as usize
}

impl Tiles {
    pub fn allocated(&self) -> usize {
        self.allocated
    }

    /// Tiles a rectangle of cells touches.
    pub fn tiles_in(rect: CellRect) -> usize {
        let (a, b) = (tile_of(rect.min), tile_of(rect.max));
        let side = |lo: i32, hi: i32| (i64::from(hi) - i64::from(lo) + 1) as usize;
        side(a.0, b.0) * side(a.1, b.1)
    }

    /// Adds `other`'s misses to these, and its hits too when `with_hits`; these must cover
    /// every tile of `other`. Refuses (false, and these counts are then partly added) when a
    /// sum would overflow, or either side has saturated: only counts that never saturated add
    /// up to what one pass of all the updates would give (a count saturates at its 65,536th
    /// update).
    pub fn add(&mut self, other: &Tiles, with_hits: bool) -> bool {
        if self.saturated || other.saturated {
            return false;
        }
        let add = |t: &mut u16, f: u16| t.checked_add(f).map(|v| *t = v).is_some();
        for (_, corner, from) in other.iter_slots() {
            let (to, _) = self.tile_mut(corner);
            let summed = to.cells.iter_mut().zip(&from.cells).all(|(t, f)| {
                add(&mut t.misses, f.misses) && (!with_hits || add(&mut t.hits, f.hits))
            });
            if !summed {
                return false;
            }
        }
        true
    }

    /// Heap bytes held: tiles and index.
    pub fn memory_bytes(&self) -> usize {
        self.allocated * TILE_BYTES + self.slots.capacity() * core::mem::size_of::<usize>()
    }

    /// Tiles in `rect` that are not allocated yet: an upper bound on what inserting beams
    /// inside `rect` can allocate, so a scan can be refused before it changes anything.
    pub fn missing_in(&self, rect: CellRect) -> usize {
        let (a, b) = (tile_of(rect.min), tile_of(rect.max));
        let mut n = 0;
        for tj in a.1..=b.1 {
            for ti in a.0..=b.0 {
                if self.slot(ti, tj).is_none_or(|k| self.slots[k].is_none()) {
                    n += 1;
                }
            }
        }
        n
    }

    fn slot(&self, ti: i32, tj: i32) -> Option<usize> {
        self.slot_wide(i64::from(ti), i64::from(tj))
    }

    /// The index slot of tile (`ti`, `tj`), `None` outside the index; wide coordinates so that
    /// a walk may ask about cells beyond the i32 range.
    #[inline]
    pub fn slot_wide(&self, ti: i64, tj: i64) -> Option<usize> {
        let (u, v) = (ti - i64::from(self.ti0), tj - i64::from(self.tj0));
        (u >= 0 && v >= 0 && (u as usize) < self.tw && (v as usize) < self.th)
            .then(|| v as usize * self.tw + u as usize)
    }

    /// Slots in the index (allocated or not).
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    /// Grows the index to cover `rect` (the caller has checked its size against the extent
    /// limit). Only pointers move; tiles stay where they are.
    pub fn cover(&mut self, rect: CellRect) {
        let (a, b) = (tile_of(rect.min), tile_of(rect.max));
        if self.slot(a.0, a.1).is_some() && self.slot(b.0, b.1).is_some() {
            return;
        }
        let (ti0, tj0, ti1, tj1) = if self.tw == 0 {
            (a.0, a.1, b.0, b.1)
        } else {
            (
                a.0.min(self.ti0),
                a.1.min(self.tj0),
                b.0.max(self.ti0 + self.tw as i32 - 1),
                b.1.max(self.tj0 + self.th as i32 - 1),
            )
        };
        let (tw, th) = ((ti1 - ti0 + 1) as usize, (tj1 - tj0 + 1) as usize);
        let mut slots: Vec<Option<Box<Tile>>> = Vec::new();
        slots.resize_with(tw * th, || None);
        for (k, tile) in self.slots.drain(..).enumerate() {
            let (u, v) = ((k % self.tw) as i32, (k / self.tw) as i32);
            let (ti, tj) = (self.ti0 + u, self.tj0 + v);
            slots[(tj - tj0) as usize * tw + (ti - ti0) as usize] = tile;
        }
        (self.ti0, self.tj0, self.tw, self.th, self.slots) = (ti0, tj0, tw, th, slots);
    }

    /// The tile holding `c` and the cell's offset in it, allocating the tile on first use.
    /// `c` must lie inside the covered rectangle.
    #[inline]
    fn tile_mut(&mut self, c: Cell) -> (&mut Tile, usize) {
        let (ti, tj) = tile_of(c);
        let k = (tj - self.tj0) as usize * self.tw + (ti - self.ti0) as usize;
        let slot = &mut self.slots[k];
        if slot.is_none() {
            self.allocated += 1;
        }
        (slot.get_or_insert_with(Tile::new), offset_in_tile(c))
    }

    /// One beam passed through `c`.
    #[inline]
    pub fn add_miss(&mut self, c: Cell) {
        let (t, k) = self.tile_mut(c);
        let cell = &mut t.cells[k];
        let full = cell.misses == u16::MAX;
        if full {
            cell.halve();
        }
        cell.misses += 1;
        self.saturated |= full;
    }

    /// One miss in every cell of the line from `from` up to, not including, `to` (and in `to`
    /// as well when `end_too`): the cells of [`super::raycast::trace`], walked in runs that stay
    /// inside one tile so that the tile is looked up once a run (up to 64 cells) and each cell
    /// costs an increment, a compare and two adds. Both cells must lie inside the covered
    /// rectangle.
    ///
    /// Cells holding at least `solid_hits` hits (0: none) are set aside in `solid` (a buffer
    /// reused between calls) and gain their miss only if the line crosses the surface that made
    /// them: if more of their two neighbours along the line's major axis hold such hits than of
    /// their two neighbours across it, the surface there runs along the line (within 45° of
    /// it), and a beam that runs along a surface says nothing about it. A wall is a line of
    /// zero thickness in a cell; a beam crossing it steeply meets it in any cell where both
    /// lie, but a beam grazing it can pass through the wall's cells beside it, and the lidar
    /// returns nothing from a surface at grazing incidence, so such beams would wear away the
    /// end of every wall they pass at a shallow angle (the jambs of a door seen from along
    /// the wall). A wall seen face on, whose hits spread over a cell or two in depth, and a
    /// person seen from the front (a short arc) extend across the beams that cross them.
    pub fn add_misses_along(
        &mut self,
        from: Cell,
        to: Cell,
        end_too: bool,
        solid_hits: u16,
        solid: &mut Vec<(i64, Cell)>,
    ) {
        let line = Line::new(from, to);
        let Line {
            major,
            minor,
            major_step,
            minor_step,
        } = line;
        let offset_step = |(di, dj): (i32, i32)| di as isize + (dj as isize) * TILE as isize;
        // A step moves the offset in the tile one way or the other, and the decision variable
        // with it, by whether the line passed half a cell: two selects and two adds a cell.
        let straight = (offset_step(major_step), 2 * minor);
        let diagonal_off = offset_step(major_step) + offset_step(minor_step);
        let slanted = (diagonal_off, 2 * minor - 2 * major);
        let diagonal = (major_step.0 + minor_step.0, major_step.1 + minor_step.1);
        let threshold = if solid_hits == 0 {
            u32::MAX
        } else {
            u32::from(solid_hits)
        };
        solid.clear();
        let mut err = line.first_err();
        let mut cell = from;
        let mut left = major;
        while left > 0 {
            let run = run_in_tile(cell, left, diagonal);
            let first = major - left;
            let err_before = err;
            let corner = Cell::new(cell.i & !TILE_MASK, cell.j & !TILE_MASK);
            let (tile, k) = self.tile_mut(cell);
            let mut off = k as isize;
            let mut saturated = false;
            for t in first..first + run {
                // The run stays inside the tile, so the mask changes no offset; it only spares
                // the bounds check.
                let o = off as usize & (TILE_CELLS - 1);
                let counts = &mut tile.cells[o];
                if u32::from(counts.hits) >= threshold {
                    solid.push((t, cell_at(corner, o)));
                } else {
                    if counts.misses == u16::MAX {
                        counts.halve();
                        saturated = true;
                    }
                    counts.misses += 1;
                }
                let (off_step, err_step) = if err > 0 { slanted } else { straight };
                off += off_step;
                err += err_step;
            }
            self.saturated |= saturated;
            // The minor-axis steps taken in the run, from the decision variable's change.
            let minor_steps = (err_before + run * 2 * minor - err) / (2 * major);
            let moved = |a: i32, b: i32| (i64::from(a) * run + i64::from(b) * minor_steps) as i32;
            cell = Cell::new(
                cell.i + moved(major_step.0, minor_step.0),
                cell.j + moved(major_step.1, minor_step.1),
            );
            left -= run;
        }
        if u32::from(self.counts(to).0) >= threshold {
            solid.push((major, to));
        } else if end_too {
            self.add_miss(to);
        }
        let across_step = (major_step.1.abs(), major_step.0.abs());
        for &(t, c) in solid.iter() {
            if t == major && !end_too {
                continue;
            }
            let (along, across) = self.solid_beside(c, major_step, across_step, threshold);
            if along <= across {
                self.add_miss(c);
            }
        }
    }

    /// How many of the two cells beside `c` one step `a` away (either way) hold at least
    /// `threshold` hits, and how many of the two one step `b` away. The four lie in `c`'s own
    /// tile unless `c` is on its edge, and are then read from it with one lookup.
    fn solid_beside(
        &self,
        c: Cell,
        a: (i32, i32),
        b: (i32, i32),
        threshold: u32,
    ) -> (usize, usize) {
        let inner = |v: i32| (1..TILE_MASK).contains(&(v & TILE_MASK));
        if let (true, true, Some(tile)) = (inner(c.i), inner(c.j), self.tile_at(c)) {
            let k = offset_in_tile(c) as isize;
            let solid = |di: i32, dj: i32| {
                let o = k + di as isize + dj as isize * TILE as isize;
                usize::from(u32::from(tile.cells[o as usize].hits) >= threshold)
            };
            let pair = |(di, dj): (i32, i32)| solid(di, dj) + solid(-di, -dj);
            return (pair(a), pair(b));
        }
        let solid =
            |i: i32, j: i32| usize::from(u32::from(self.counts(Cell::new(i, j)).0) >= threshold);
        let pair = |(di, dj): (i32, i32)| solid(c.i + di, c.j + dj) + solid(c.i - di, c.j - dj);
        (pair(a), pair(b))
    }

    /// The most hits any cell of the 3 x 3 block centred on `c` holds (cells beyond the
    /// coordinate range left out). The nine lie in `c`'s own tile unless `c` is on its edge,
    /// and are then read from it with one lookup.
    pub fn most_hits_around(&self, c: Cell) -> u16 {
        let inner = |v: i32| (1..TILE_MASK).contains(&(v & TILE_MASK));
        if let (true, true, Some(tile)) = (inner(c.i), inner(c.j), self.tile_at(c)) {
            let k = offset_in_tile(c);
            let row = |o: usize| {
                let r = &tile.cells[o - 1..=o + 1];
                r[0].hits.max(r[1].hits).max(r[2].hits)
            };
            return row(k - TILE).max(row(k)).max(row(k + TILE));
        }
        let mut most = 0;
        for dj in -1..=1 {
            for di in -1..=1 {
                let n = Cell::new(c.i.saturating_add(di), c.j.saturating_add(dj));
                most = most.max(self.counts(n).0);
            }
        }
        most
    }

    /// Allocates every tile the line from `from` to `to` passes through (the cells of
    /// [`Self::add_misses_along`]), counting nothing. Both cells must lie inside the covered
    /// rectangle.
    pub fn allocate_along(&mut self, from: Cell, to: Cell) {
        let line = Line::new(from, to);
        let diagonal = (
            line.major_step.0 + line.minor_step.0,
            line.major_step.1 + line.minor_step.1,
        );
        let mut err = line.first_err();
        let mut cell = from;
        let mut left = line.major;
        self.tile_mut(to);
        while left > 0 {
            self.tile_mut(cell);
            let run = run_in_tile(cell, left, diagonal);
            let mut minor_steps = 0i64;
            for _ in 0..run {
                if err > 0 {
                    err -= 2 * line.major;
                    minor_steps += 1;
                }
                err += 2 * line.minor;
            }
            let moved = |a: i32, b: i32| (i64::from(a) * run + i64::from(b) * minor_steps) as i32;
            cell = Cell::new(
                cell.i + moved(line.major_step.0, line.minor_step.0),
                cell.j + moved(line.major_step.1, line.minor_step.1),
            );
            left -= run;
        }
    }

    /// One beam ended in `c`.
    #[inline]
    pub fn add_hit(&mut self, c: Cell) {
        let (t, k) = self.tile_mut(c);
        let cell = &mut t.cells[k];
        let full = cell.hits == u16::MAX;
        if full {
            cell.halve();
        }
        cell.hits += 1;
        self.saturated |= full;
    }

    /// Adds up to `n` misses to `c` one at a time, as [`Self::add_miss`] would, while the cell's
    /// hits stay in `hits` (halving at saturation can take them out).
    pub fn add_misses_while(&mut self, c: Cell, mut n: u64, hits: core::ops::RangeInclusive<u16>) {
        let (t, k) = self.tile_mut(c);
        let cell = &mut t.cells[k];
        let mut saturated = false;
        while n > 0 && hits.contains(&cell.hits) {
            let room = u64::from(u16::MAX - cell.misses);
            if n <= room {
                cell.misses += n as u16;
                break;
            }
            cell.misses = u16::MAX;
            cell.halve();
            cell.misses += 1;
            n -= room + 1;
            saturated = true;
        }
        self.saturated |= saturated;
    }

    /// (hits, misses) of a cell; (0, 0) where nothing was ever observed.
    pub fn counts(&self, c: Cell) -> (u16, u16) {
        match self.tile_at(c) {
            Some(t) => {
                let k = offset_in_tile(c);
                (t.cells[k].hits, t.cells[k].misses)
            }
            None => (0, 0),
        }
    }

    /// The tile holding `c`, `None` where none is allocated.
    pub fn tile_at(&self, c: Cell) -> Option<&Tile> {
        let (ti, tj) = tile_of(c);
        self.slot(ti, tj).and_then(|k| self.slots[k].as_deref())
    }

    /// Every allocated tile with the cell of its lower-left corner.
    pub fn iter(&self) -> impl Iterator<Item = (Cell, &Tile)> + '_ {
        self.iter_slots().map(|(_, corner, t)| (corner, t))
    }

    /// Every allocated tile with its index slot and the cell of its lower-left corner.
    pub fn iter_slots(&self) -> impl Iterator<Item = (usize, Cell, &Tile)> + '_ {
        self.slots.iter().enumerate().filter_map(move |(k, t)| {
            let (u, v) = ((k % self.tw) as i32, (k / self.tw) as i32);
            let corner = Cell::new((self.ti0 + u) << TILE_SHIFT, (self.tj0 + v) << TILE_SHIFT);
            t.as_deref().map(|t| (k, corner, t))
        })
    }
}

/// Steps of a line at `cell` (with `left` steps to go, each moving each coordinate by at most
/// the matching one of `diagonal`) that stay inside the cell's tile: at least 1.
fn run_in_tile(cell: Cell, left: i64, diagonal: (i32, i32)) -> i64 {
    // Steps possible along one axis before leaving the tile (unbounded on a still axis).
    let room = |local: i32, step: i32| match step {
        1 => (TILE_MASK - local) as i64,
        -1 => local as i64,
        _ => i64::MAX,
    };
    let (i, j) = (cell.i & TILE_MASK, cell.j & TILE_MASK);
    left.min(1 + room(i, diagonal.0).min(room(j, diagonal.1)))
}

/// The cell at offset `k` of the tile whose lower-left cell is `corner`.
pub fn cell_at(corner: Cell, k: usize) -> Cell {
    Cell::new(
        corner.i + (k & (TILE - 1)) as i32,
        corner.j + (k >> TILE_SHIFT) as i32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::raycast::trace;
    use proptest::prelude::*;

    proptest! {
        /// The tile-run walk adds exactly the misses of the reference line, across tile
        /// borders and on both sides of zero, and allocates the tiles it passes, as many as
        /// allocating along the line does.
        #[test]
        fn runs_inside_tiles_add_the_reference_lines_misses(
            ai in -200i32..200, aj in -200i32..200, bi in -200i32..200, bj in -200i32..200,
        ) {
            let (a, b) = (Cell::new(ai, aj), Cell::new(bi, bj));
            let rect = CellRect::of(a).union(CellRect::of(b));
            let (mut fast, mut reference) = (Tiles::default(), Tiles::default());
            fast.cover(rect);
            reference.cover(rect);
            let mut solid = Vec::new();
            fast.add_misses_along(a, b, false, 0, &mut solid);
            fast.add_misses_along(a, b, true, 0, &mut solid);
            trace(a, b, |c| { reference.add_miss(c); reference.add_miss(c); });
            reference.add_miss(b);
            let mut allocated = Tiles::default();
            allocated.cover(rect);
            allocated.allocate_along(a, b);
            prop_assert_eq!(allocated.allocated(), fast.allocated(), "the same tiles");
            for j in rect.min.j..=rect.max.j {
                for i in rect.min.i..=rect.max.i {
                    let c = Cell::new(i, j);
                    prop_assert_eq!(fast.counts(c), reference.counts(c), "{:?}", c);
                }
            }
        }
    }

    proptest! {
        /// The surface rule's count of solid cells beside a cell is the same whether the four
        /// are read from the cell's own tile or looked up one by one, at tile edges and
        /// corners too.
        #[test]
        fn cells_beside_read_alike_inside_a_tile_and_across_its_edges(
            hits in prop::collection::vec((near_edges(), near_edges(), 1u16..6), 1..60),
            pick in 0usize..60,
            steep in any::<bool>(),
            sign in prop::sample::select(vec![-1i32, 1]),
        ) {
            let mut t = Tiles::default();
            t.cover(CellRect { min: Cell::new(-71, -71), max: Cell::new(71, 71) });
            for &(i, j, n) in &hits {
                (0..n).for_each(|_| t.add_hit(Cell::new(i, j)));
            }
            let (i, j, _) = hits[pick % hits.len()];
            let c = Cell::new(i, j);
            let a = if steep { (0, sign) } else { (sign, 0) };
            let b = (a.1.abs(), a.0.abs());
            let one_by_one = |(di, dj): (i32, i32)| {
                [1, -1]
                    .iter()
                    .filter(|&&s| t.counts(Cell::new(c.i + s * di, c.j + s * dj)).0 >= 3)
                    .count()
            };
            prop_assert_eq!(t.solid_beside(c, a, b, 3), (one_by_one(a), one_by_one(b)));
        }
    }

    proptest! {
        /// The most hits around a cell are the same whether the nine are read from the cell's
        /// own tile or looked up one by one, at tile edges and corners too.
        #[test]
        fn most_hits_around_read_alike_inside_a_tile_and_across_its_edges(
            hits in prop::collection::vec((near_edges(), near_edges(), 1u16..6), 1..60),
            i in near_edges(),
            j in near_edges(),
        ) {
            let mut t = Tiles::default();
            t.cover(CellRect { min: Cell::new(-71, -71), max: Cell::new(71, 71) });
            for &(i, j, n) in &hits {
                (0..n).for_each(|_| t.add_hit(Cell::new(i, j)));
            }
            let one_by_one = (-1..=1)
                .flat_map(|dj| (-1..=1).map(move |di| (di, dj)))
                .map(|(di, dj)| t.counts(Cell::new(i + di, j + dj)).0)
                .max()
                .unwrap_or(0);
            prop_assert_eq!(t.most_hits_around(Cell::new(i, j)), one_by_one);
        }
    }

    /// Coordinates on both sides of tile edges, so that cells beside each other crowd there.
    fn near_edges() -> impl Strategy<Value = i32> {
        prop::sample::select(vec![-66, -65, -64, -63, -2, -1, 0, 1, 2, 62, 63, 64, 65])
    }

    #[test]
    fn counts_land_in_their_cell_across_tiles_and_the_index_grows_without_moving_them() {
        let mut t = Tiles::default();
        let cells = [
            Cell::new(0, 0),
            Cell::new(-1, -1),
            Cell::new(63, 64),
            Cell::new(-200, 150),
        ];
        for (n, &c) in cells.iter().enumerate() {
            t.cover(CellRect::of(c));
            for _ in 0..=n {
                t.add_hit(c);
            }
            t.add_miss(c);
        }
        for (n, &c) in cells.iter().enumerate() {
            assert_eq!(t.counts(c), (n as u16 + 1, 1), "{c:?}");
        }
        assert_eq!(t.counts(Cell::new(1, 0)), (0, 0));
        assert_eq!(t.counts(Cell::new(10_000, 0)), (0, 0));
        assert_eq!(t.allocated(), 4);
        let found: Vec<Cell> = t
            .iter()
            .flat_map(|(corner, tile)| {
                (0..TILE_CELLS)
                    .filter(|&k| tile.cells[k].hits > 0)
                    .map(move |k| cell_at(corner, k))
            })
            .collect();
        assert_eq!(found.len(), 4);
        assert!(cells.iter().all(|c| found.contains(c)));
    }

    #[test]
    fn saturating_counts_keep_their_ratio() {
        let mut t = Tiles::default();
        let c = Cell::new(3, 3);
        t.cover(CellRect::of(c));
        for _ in 0..3 * u32::from(u16::MAX) {
            t.add_miss(c);
            t.add_miss(c);
            t.add_hit(c);
        }
        let (h, m) = t.counts(c);
        let ratio = f64::from(h) / (f64::from(h) + f64::from(m));
        assert!((ratio - 1.0 / 3.0).abs() < 0.01, "{h} hits, {m} misses");
    }

    #[test]
    fn adding_counts_refuses_sums_that_overflow_and_counts_that_saturated() {
        let c = Cell::new(-3, 70);
        let with = |hits: u32, misses: u32| {
            let mut t = Tiles::default();
            t.cover(CellRect::of(c));
            (0..hits).for_each(|_| t.add_hit(c));
            (0..misses).for_each(|_| t.add_miss(c));
            t
        };
        let mut a = with(3, 40_000);
        assert!(a.add(&with(2, 25_535), true));
        assert_eq!(a.counts(c), (5, u16::MAX));
        assert!(
            !with(3, 40_000).add(&with(0, 25_536), true),
            "the sum overflows"
        );
        // Saturated on its own: the halving depended on what came first, so no sum is right.
        assert!(!with(1, 0).add(&with(3, 70_000), true));
        assert!(!with(3, 70_000).add(&with(1, 0), true));
    }

    #[test]
    fn missing_tiles_are_counted_before_allocation() {
        let mut t = Tiles::default();
        let r = CellRect {
            min: Cell::new(-1, -1),
            max: Cell::new(64, 0),
        };
        t.cover(r);
        assert_eq!(t.missing_in(r), 6, "tiles -1..=1 by -1..=0");
        t.add_miss(Cell::new(0, 0));
        assert_eq!(t.missing_in(r), 5);
    }
}
