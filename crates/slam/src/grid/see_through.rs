//! Seeing through the finished map ([`super::OccupancyGrid::see_through`]) without looking up
//! every cell of every beam. Only the few cells keyframes hit at most `max_hits` times can
//! change, so they are indexed first as a bit a cell in tiles of their own, hung off the
//! grid's tile index. Each beam's Bresenham line then goes tile by tile: across a tile with no
//! candidate in one jump (where a line is after any number of steps has a closed form, so the
//! jump lands on the very cell the step-by-step walk of [`super::raycast::trace`] reaches), and
//! through the others cell by cell, testing a bit of the row it is in. The misses counted are
//! added at the end with the saturation of single misses; a cell's change depends on nothing
//! but its own counts, so neither the order of the beams nor their split among threads
//! matters.

use super::frame::{Cell, GridFrame};
use super::prepared::PreparedScan;
use super::raycast::Line;
use super::tiles::{Tiles, TILE, TILE_SHIFT};
use core::ops::RangeInclusive;
use plumbline_core::geom::{Pose2, Vec2};

const NO_TILE: u32 = u32::MAX;

/// The candidate cells of one tile: bit `i` of `rows[j]` is local cell (i, j), and `first[j]`
/// is where row `j`'s cells start in [`Candidates::cells`].
struct CandidateTile {
    rows: [u64; TILE],
    first: [u32; TILE],
}

/// The cells whose hits lie in a range. The misses counted for them live in a separate array
/// ([`Candidates::counters`]), so that several threads can count for one index.
pub(super) struct Candidates {
    /// For each slot of the tiles' index: its entry in `tiles`, or [`NO_TILE`].
    slot_tile: Vec<u32>,
    tiles: Vec<CandidateTile>,
    /// Every candidate cell, tile by tile, row by row.
    cells: Vec<Cell>,
    hits: RangeInclusive<u16>,
}

impl Candidates {
    /// Indexes every cell of `tiles` whose hits lie in `hits`.
    pub fn find(tiles: &Tiles, hits: RangeInclusive<u16>) -> Candidates {
        let mut c = Candidates {
            slot_tile: vec![NO_TILE; tiles.slot_count()],
            tiles: Vec::new(),
            cells: Vec::new(),
            hits,
        };
        for (slot, corner, tile) in tiles.iter_slots() {
            let mut rows = [0u64; TILE];
            for (row, counts) in rows.iter_mut().zip(tile.cells.chunks_exact(TILE)) {
                for (i, n) in counts.iter().enumerate() {
                    *row |= u64::from(c.hits.contains(&n.hits)) << i;
                }
            }
            if rows.iter().all(|&r| r == 0) {
                continue;
            }
            let mut first = [0u32; TILE];
            for (j, &row) in rows.iter().enumerate() {
                first[j] = c.cells.len() as u32;
                let mut bits = row;
                while bits != 0 {
                    let i = bits.trailing_zeros() as i32;
                    bits &= bits - 1;
                    c.cells.push(Cell::new(corner.i + i, corner.j + j as i32));
                }
            }
            c.slot_tile[slot] = c.tiles.len() as u32;
            c.tiles.push(CandidateTile { rows, first });
        }
        c
    }

    /// A zero miss count for every candidate.
    pub fn counters(&self) -> Vec<u64> {
        vec![0; self.cells.len()]
    }

    /// Counts the misses of a scan's beams at `pose` (see [`Self::count_along`]).
    pub fn count_scan(
        &self,
        grid: (&Tiles, GridFrame, [(i64, i64); 2]),
        pose: Pose2,
        scan: &PreparedScan,
        misses: &mut [u64],
    ) {
        let (tiles, frame, span) = grid;
        let origin = frame.cell_of(pose.translation());
        let (s, c) = (pose.theta.sin(), pose.theta.cos());
        for p in scan.hits().iter().chain(scan.clears()) {
            let w = Vec2::new(c * p.x - s * p.y + pose.x, s * p.x + c * p.y + pose.y);
            self.count_along(tiles, span, origin, frame.cell_of(w), misses);
        }
    }

    /// The candidate tile holding `cell`, if it has candidates.
    fn tile_at(&self, tiles: &Tiles, (i, j): (i64, i64)) -> Option<&CandidateTile> {
        let slot = tiles.slot_wide(i >> TILE_SHIFT, j >> TILE_SHIFT)?;
        let t = self.slot_tile[slot];
        (t != NO_TILE).then(|| &self.tiles[t as usize])
    }

    /// Counts a miss for every candidate on the line from `from` up to, not including, `to`
    /// (the cells [`super::raycast::trace`] visits). Only cells inside `span` (the inclusive
    /// cell range along x and along y that holds every candidate) are walked.
    pub fn count_along(
        &self,
        tiles: &Tiles,
        span: [(i64, i64); 2],
        from: Cell,
        to: Cell,
        misses: &mut [u64],
    ) {
        let line = Line::new(from, to);
        // The steps whose major-axis coordinate lies inside the span.
        let axis = usize::from(line.major_step.0 == 0);
        let (lo, hi) = span[axis];
        let start = [i64::from(from.i), i64::from(from.j)][axis];
        let (a, b) = if line.major_step.0 + line.major_step.1 > 0 {
            (lo - start, hi - start)
        } else {
            (start - hi, start - lo)
        };
        let end = (b + 1).min(line.major);
        let mut walk = Walk::at(&line, from, a.max(0));
        while walk.t < end {
            let run = walk.steps_in_square(TILE_SHIFT).min(end - walk.t);
            match self.tile_at(tiles, walk.cell) {
                None => walk.advance(run),
                Some(tile) => walk.count_in_tile(tile, run, misses),
            }
        }
    }

    /// Adds the counted misses to the tiles.
    pub fn apply(&self, misses: &[u64], tiles: &mut Tiles) {
        for (&cell, &n) in self.cells.iter().zip(misses) {
            if n > 0 {
                tiles.add_misses_while(cell, n, self.hits.clone());
            }
        }
    }
}

/// A Bresenham line in closed form. Before step `t` it has taken `y = round(t minor / major)`
/// steps along the minor axis, halves rounded down (what the decision variable of
/// [`super::raycast::trace`] gives); the walk keeps `y` as the cell it leads to and the
/// remainder `r` of `2 minor t + major - 1 = 2 major y + r`, `0 <= r < 2 major`, so that every
/// jump is a division of small numbers.
struct Walk {
    /// Twice the major and minor lengths.
    major2: i64,
    minor2: i64,
    major_dir: (i64, i64),
    /// The minor axis, signed as the line goes (any sign on a line with no minor steps).
    minor_dir: (i64, i64),
    t: i64,
    r: i64,
    cell: (i64, i64),
}

impl Walk {
    /// The line before step `t` (`t >= 0`).
    fn at(line: &Line, from: Cell, t: i64) -> Walk {
        let (major, minor) = (line.major, line.minor);
        let v = |(a, b): (i32, i32)| (i64::from(a), i64::from(b));
        let major_dir = v(line.major_step);
        let minor_dir = if minor == 0 {
            (major_dir.1.abs(), major_dir.0.abs())
        } else {
            v(line.minor_step)
        };
        let (y, r) = if t == 0 {
            (0, major - 1)
        } else {
            // In i128: t and the lengths may each approach 2^32.
            let n = 2 * i128::from(minor) * i128::from(t) + i128::from(major) - 1;
            let d = 2 * i128::from(major).max(1);
            (n.div_euclid(d) as i64, n.rem_euclid(d) as i64)
        };
        Walk {
            major2: 2 * major,
            minor2: 2 * minor,
            major_dir,
            minor_dir,
            t,
            r,
            cell: (
                i64::from(from.i) + t * major_dir.0 + y * minor_dir.0,
                i64::from(from.j) + t * major_dir.1 + y * minor_dir.1,
            ),
        }
    }

    /// Steps from here that stay inside the aligned square of side `1 << shift` holding the
    /// current cell: at least 1.
    fn steps_in_square(&self, shift: u32) -> i64 {
        let side = 1i64 << shift;
        let room = |(di, dj): (i64, i64)| {
            let (a, dir) = if di != 0 {
                (self.cell.0, di)
            } else {
                (self.cell.1, dj)
            };
            if dir > 0 {
                side - 1 - (a & (side - 1))
            } else {
                a & (side - 1)
            }
        };
        let major_steps = room(self.major_dir) + 1;
        if self.minor2 == 0 {
            return major_steps;
        }
        // The least u with r + minor2 u >= major2 k: k minor steps take it out of the square.
        let k = room(self.minor_dir) + 1;
        let minor_steps = (self.major2 * k - self.r + self.minor2 - 1) / self.minor2;
        major_steps.min(minor_steps)
    }

    /// Takes `run` steps inside `tile` (they must stay in it), as [`super::raycast::trace`]
    /// takes them, counting a miss for each candidate cell they visit.
    fn count_in_tile(&mut self, tile: &CandidateTile, run: i64, misses: &mut [u64]) {
        let mask = TILE as i64 - 1;
        let (mut i, mut j) = (self.cell.0 & mask, self.cell.1 & mask);
        let (i0, j0) = (i, j);
        let mut r = self.r;
        for _ in 0..run {
            let row = tile.rows[j as usize];
            if (row >> i) & 1 != 0 {
                let before = row & ((1u64 << i) - 1);
                misses[tile.first[j as usize] as usize + before.count_ones() as usize] += 1;
            }
            r += self.minor2;
            let minor_step = i64::from(r >= self.major2);
            r -= minor_step * self.major2;
            i += self.major_dir.0 + minor_step * self.minor_dir.0;
            j += self.major_dir.1 + minor_step * self.minor_dir.1;
        }
        self.t += run;
        self.r = r;
        self.cell.0 += i - i0;
        self.cell.1 += j - j0;
    }

    fn advance(&mut self, steps: i64) {
        let n = self.r + self.minor2 * steps;
        let (y, r) = (n / self.major2, n % self.major2);
        self.t += steps;
        self.r = r;
        self.cell.0 += steps * self.major_dir.0 + y * self.minor_dir.0;
        self.cell.1 += steps * self.major_dir.1 + y * self.minor_dir.1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::frame::CellRect;
    use crate::grid::raycast::trace;
    use proptest::prelude::*;

    /// The definition: each line walked cell by cell, each candidate gaining a miss at once.
    fn step_by_step(tiles: &mut Tiles, lines: &[(Cell, Cell)], hits: RangeInclusive<u16>) {
        for &(a, b) in lines {
            trace(a, b, |c| {
                if hits.contains(&tiles.counts(c).0) {
                    tiles.add_miss(c);
                }
            });
        }
    }

    fn cell() -> impl Strategy<Value = Cell> {
        (-330i32..330, -330i32..330).prop_map(|(i, j)| Cell::new(i, j))
    }

    proptest! {
        /// Counting along jumps and adding at the end gives every cell the counts of the
        /// step-by-step walk, for lines inside, across and outside the mapped area.
        #[test]
        fn jumps_count_the_misses_of_the_step_by_step_walk(
            seeds in prop::collection::vec((cell(), 1u16..5), 1..120),
            lines in prop::collection::vec((cell(), cell()), 1..40),
            max_hits in 1u16..4,
            pattern in any::<u64>(),
        ) {
            let rect = CellRect { min: Cell::new(-200, -150), max: Cell::new(150, 200) };
            let mut tiles = Tiles::default();
            tiles.cover(rect);
            for &(c, h) in &seeds {
                let c = Cell::new(c.i.clamp(-200, 150), c.j.clamp(-150, 200));
                for _ in 0..h {
                    tiles.add_hit(c);
                }
            }
            // A dense patch with about a third of its cells candidates, where a jump that
            // lands one cell off shows at once.
            for j in -40..40 {
                for i in -40..40 {
                    let h = (pattern ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
                        .wrapping_mul(0x1656_67B1_9E37_79F9) >> 61;
                    for _ in 0..h {
                        tiles.add_hit(Cell::new(i, j));
                    }
                }
            }
            // Lines from the seeds too, so that many pass through candidates.
            let mut all = lines.clone();
            all.extend(seeds.iter().zip(&lines).map(|(s, l)| (l.0, s.0)));
            // Level, upright and diagonal lines through the seeds, both ways.
            for &(Cell { i, j }, _) in &seeds {
                all.push((Cell::new(i - 70, j), Cell::new(i + 9, j)));
                all.push((Cell::new(i, j + 60), Cell::new(i, j - 3)));
                all.push((Cell::new(i - 40, j + 40), Cell::new(i + 5, j - 5)));
            }
            let mut reference = tiles.clone();
            step_by_step(&mut reference, &all, 1..=max_hits);
            let candidates = Candidates::find(&tiles, 1..=max_hits);
            let mut misses = candidates.counters();
            let span = [(-200, 150), (-150, 200)];
            for &(a, b) in &all {
                candidates.count_along(&tiles, span, a, b, &mut misses);
            }
            candidates.apply(&misses, &mut tiles);
            for j in rect.min.j..=rect.max.j {
                for i in rect.min.i..=rect.max.i {
                    let c = Cell::new(i, j);
                    prop_assert_eq!(tiles.counts(c), reference.counts(c), "{:?}", c);
                }
            }
        }
    }

    #[test]
    fn lines_from_far_outside_count_only_inside() {
        let rect = CellRect {
            min: Cell::new(-70, -70),
            max: Cell::new(70, 70),
        };
        let mut tiles = Tiles::default();
        tiles.cover(rect);
        for k in -60..60 {
            tiles.add_hit(Cell::new(k, (k * 7) % 50));
            tiles.add_hit(Cell::new(k / 3, k));
        }
        let lines = [
            (Cell::new(-90_000, -31_000), Cell::new(40, 11)),
            (Cell::new(75_001, 60), Cell::new(-65_000, -20)),
            (Cell::new(3, 99_999), Cell::new(-2, -99_998)),
            (Cell::new(0, 0), Cell::new(80_000, 79_999)),
        ];
        let mut reference = tiles.clone();
        step_by_step(&mut reference, &lines, 1..=2);
        let candidates = Candidates::find(&tiles, 1..=2);
        let mut misses = candidates.counters();
        for &(a, b) in &lines {
            candidates.count_along(&tiles, [(-70, 70), (-70, 70)], a, b, &mut misses);
        }
        candidates.apply(&misses, &mut tiles);
        let mut changed = 0;
        for j in rect.min.j..=rect.max.j {
            for i in rect.min.i..=rect.max.i {
                let c = Cell::new(i, j);
                assert_eq!(tiles.counts(c), reference.counts(c), "{c:?}");
                changed += usize::from(tiles.counts(c).1 > 0);
            }
        }
        assert!(changed > 0, "the lines cross candidates");
    }

    #[test]
    fn many_misses_at_once_saturate_as_single_ones() {
        for (hits, misses, n) in [
            (2u16, 65_530u16, 70_000u64),
            (1, 65_000, 200_000),
            (2, 0, 9),
        ] {
            let c = Cell::new(5, -3);
            let mut one_by_one = Tiles::default();
            one_by_one.cover(CellRect::of(c));
            for _ in 0..hits {
                one_by_one.add_hit(c);
            }
            for _ in 0..misses {
                one_by_one.add_miss(c);
            }
            let mut at_once = one_by_one.clone();
            for _ in 0..n {
                if (1..=2).contains(&one_by_one.counts(c).0) {
                    one_by_one.add_miss(c);
                }
            }
            at_once.add_misses_while(c, n, 1..=2);
            assert_eq!(
                at_once.counts(c),
                one_by_one.counts(c),
                "{hits} hits {misses} misses + {n}"
            );
        }
    }
}
