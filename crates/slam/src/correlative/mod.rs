//! Correlative scan matching with branch and bound (Olson 2009; Hess et al. 2016, sec. V):
//! the exhaustive answer to "where in this window does the scan fit best", without visiting
//! every pose.
//!
//! The reference points are stamped into a likelihood grid (a Gaussian of the distance to the
//! nearest point, one byte a cell). Level `k` of the pyramid holds, at each cell, the largest
//! value in the `2^k × 2^k` block starting there, so scoring a scan against level `k` at one
//! translation bounds its score at every translation in that block from above. The search
//! starts with coarse blocks for every heading, always expands the best bound first, and drops
//! any block whose bound cannot beat the best complete answer: the result is the best pose on
//! the fine grid, exactly, at a small fraction of the cost of scoring them all.

mod likelihood;

use plumbline_core::geom::{Pose2, Vec2};

/// How the grid is made and searched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrelativeConfig {
    /// Cell edge of the fine grid, m; also the translation step of the answer.
    pub resolution_m: f32,
    /// Spread of a point's likelihood, m.
    pub sigma_m: f32,
    /// Score at most this many current points (every k-th of a denser scan).
    pub max_points: usize,
    /// Points farther than this are not scored, m: the heading step must move the farthest
    /// scored point by about a cell, so one wall at 40 m would multiply the headings searched.
    pub max_range_m: f32,
}

impl Default for CorrelativeConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.1,
            sigma_m: 0.1,
            max_points: 90,
            max_range_m: 10.0,
        }
    }
}

/// The search window around a guess.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub translation_m: f32,
    pub heading_rad: f32,
}

/// What a pose's distance from the motion guess costs, in mean likelihood (the score's units):
/// of poses that fit about equally well, such as places along a featureless corridor or a
/// corridor seen looking back the way the vehicle came (a 180° lidar sees much the same
/// there), the one nearer the guess wins. This is the motion model's term of Olson's (2009)
/// posterior, as a quadratic penalty; the search stays exact, since a block's bound
/// subtracts the least penalty of any pose in it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionPrior {
    /// Score lost per square metre of translation and per square radian of turn.
    pub per_m2: f32,
    pub per_rad2: f32,
}

/// The best pose found and how well the scan fits there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    pub pose: Pose2,
    /// Mean likelihood of the scored points, 0 to 1 (1: every point exactly on a reference point).
    pub score: f32,
}

/// Likelihood grid of a reference point set with its max pyramid.
pub struct LookupGrid {
    origin: Vec2,
    resolution: f32,
    width: i32,
    height: i32,
    /// `levels[k]` is the max over `2^k × 2^k` blocks of `levels[0]`.
    levels: Vec<Vec<u8>>,
}

impl LookupGrid {
    /// The largest fine value in the block `[x, x + 2^level) × [y, y + 2^level)`, or a bound
    /// above it: a block hanging over the low edge is read from the edge cell, whose block covers
    /// the part inside.
    fn value(&self, level: usize, x: i32, y: i32) -> u8 {
        let size = 1i32 << level;
        if x + size <= 0 || y + size <= 0 || x >= self.width || y >= self.height {
            return 0;
        }
        let (x, y) = (x.max(0), y.max(0));
        self.levels[level][(y * self.width + x) as usize]
    }

    /// The best pose of `points` (current scan, own frame) within `window` of `guess`, if any
    /// scores at least `min_score`.
    pub fn search(
        &self,
        points: &[Vec2],
        guess: Pose2,
        window: Window,
        min_score: f32,
        config: &CorrelativeConfig,
    ) -> Option<Found> {
        let prior = MotionPrior::default();
        self.search_near(points, guess, window, prior, min_score, config)
    }

    /// The pose that fits best once poses away from the guess are penalised by `prior`, if its
    /// penalised score reaches `min_score`; the score returned is its own fit, unpenalised.
    pub fn search_near(
        &self,
        points: &[Vec2],
        guess: Pose2,
        window: Window,
        prior: MotionPrior,
        min_score: f32,
        config: &CorrelativeConfig,
    ) -> Option<Found> {
        let layout = self.layout(points, guess, window, prior, config)?;
        let threshold = (min_score * layout.norm) as u32;
        let best = self.run(&layout, threshold, None)?;
        Some(layout.found(self, best, guess))
    }

    /// The score of the best pose at least `exclude_m` or `exclude_rad` away from `winner` (a
    /// [`Self::search`] answer with the same arguments) that reaches `ratio` of its score, if
    /// one does: a second place almost as good means the scan fits two places (a row of alike
    /// rooms), and the winner may be the wrong one.
    pub fn rival(
        &self,
        points: &[Vec2],
        guess: Pose2,
        window: Window,
        winner: &Found,
        rival: Rival,
        config: &CorrelativeConfig,
    ) -> Option<f32> {
        let layout = self.layout(points, guess, window, MotionPrior::default(), config)?;
        let around = layout.candidate_of(self, winner.pose, guess);
        let exclusion = Exclusion {
            around,
            cells: (rival.exclude_m / self.resolution).ceil() as i32,
            headings: (rival.exclude_rad / layout.heading_step).ceil() as i32,
        };
        let floor = (winner.score * rival.ratio * layout.norm) as u32;
        self.run(&layout, floor, Some(exclusion))
            .map(|c| c.bound as f32 / layout.norm)
    }

    /// The scored points' cells for every heading of the window.
    fn layout(
        &self,
        points: &[Vec2],
        guess: Pose2,
        window: Window,
        prior: MotionPrior,
        config: &CorrelativeConfig,
    ) -> Option<Layout> {
        let scored = self.scored_points(points, config);
        if scored.is_empty() {
            return None;
        }
        let reach = scored
            .iter()
            .map(|p| p.norm())
            .fold(0.0f32, f32::max)
            .max(1.0);
        // The heading step that moves the farthest point by about one cell.
        let cos_step = 1.0 - self.resolution * self.resolution / (2.0 * reach * reach);
        let heading_step = cos_step.clamp(-1.0, 1.0).acos().max(1e-4);
        let headings = (window.heading_rad / heading_step).ceil() as i32;
        let cells: Vec<Vec<(i32, i32)>> = (-headings..=headings)
            .map(|h| {
                let rotation =
                    Pose2::new(guess.x, guess.y, guess.theta + h as f32 * heading_step).placement();
                scored
                    .iter()
                    .map(|&p| {
                        let q = rotation.transform(p);
                        (
                            ((q.x - self.origin.x) / self.resolution).floor() as i32,
                            ((q.y - self.origin.y) / self.resolution).floor() as i32,
                        )
                    })
                    .collect()
            })
            .collect();
        let half = (window.translation_m / self.resolution).ceil() as i32;
        // Each heading's cells that stay on the grid at every offset of the window first.
        let on_grid = |(x, y): (i32, i32)| {
            x.checked_sub(half).is_some_and(|lo| lo >= 0)
                && x.checked_add(half).is_some_and(|hi| hi < self.width)
                && y.checked_sub(half).is_some_and(|lo| lo >= 0)
                && y.checked_add(half).is_some_and(|hi| hi < self.height)
        };
        let (cells, on_grid): (Vec<_>, Vec<_>) = cells
            .into_iter()
            .map(|c: Vec<(i32, i32)>| {
                let (mut inside, outside): (Vec<_>, Vec<_>) =
                    c.into_iter().partition(|&c| on_grid(c));
                let count = inside.len();
                inside.extend(outside);
                (inside, count)
            })
            .unzip();
        let norm = 255.0 * scored.len() as f32;
        let turn_cost = (-headings..=headings)
            .map(|h| (norm * prior.per_rad2 * (h as f32 * heading_step).powi(2)) as u32)
            .collect();
        Some(Layout {
            cells,
            on_grid,
            headings,
            heading_step,
            half,
            norm,
            cell_cost: norm * prior.per_m2 * self.resolution * self.resolution,
            turn_cost,
        })
    }

    /// Branch and bound over the layout: the best leaf above `threshold`, outside `exclusion`.
    fn run(
        &self,
        layout: &Layout,
        threshold: u32,
        exclusion: Option<Exclusion>,
    ) -> Option<Candidate> {
        let top = self.levels.len() - 1;
        let top_step = 1i32 << top;
        let half = layout.half;
        let mut roots: Vec<Candidate> = Vec::new();
        for (heading, cells) in layout.cells.iter().enumerate() {
            let mut ix = -half;
            while ix <= half {
                let mut iy = -half;
                while iy <= half {
                    let cost = layout.cost(heading, ix, iy, top_step);
                    // A block the penalty alone rules out is not scored.
                    let open = (layout.norm as u32).saturating_sub(cost) > threshold;
                    let on_grid = layout.on_grid[heading];
                    let score = || self.score(cells, on_grid, top, ix, iy).saturating_sub(cost);
                    let bound = if open { score() } else { 0 };
                    if bound > threshold {
                        roots.push(Candidate {
                            heading,
                            ix,
                            iy,
                            level: top,
                            bound,
                        });
                    }
                    iy += top_step;
                }
                ix += top_step;
            }
        }
        roots.sort_by_key(|c| std::cmp::Reverse(c.bound));
        let mut search = Search {
            grid: self,
            layout,
            best: (threshold, None),
            exclusion,
        };
        for root in roots {
            search.expand(root);
        }
        search.best.1
    }

    /// Mean likelihood of `points` placed at `pose` on the fine grid, 0 to 1.
    pub fn score_pose(&self, points: &[Vec2], pose: Pose2, config: &CorrelativeConfig) -> f32 {
        let scored = self.scored_points(points, config);
        if scored.is_empty() {
            return 0.0;
        }
        let pose = pose.placement();
        let sum: u32 = scored
            .iter()
            .map(|&p| {
                let q = pose.transform(p);
                let x = ((q.x - self.origin.x) / self.resolution).floor() as i32;
                let y = ((q.y - self.origin.y) / self.resolution).floor() as i32;
                self.value(0, x, y) as u32
            })
            .sum();
        sum as f32 / (255.0 * scored.len() as f32)
    }

    /// The points a search scores: finite, within range, thinned to at most `max_points`.
    fn scored_points(&self, points: &[Vec2], config: &CorrelativeConfig) -> Vec<Vec2> {
        let near = |p: &Vec2| p.is_finite() && p.norm() <= config.max_range_m;
        let count = points.iter().filter(|p| near(p)).count();
        let stride = count.div_ceil(config.max_points.max(1)).max(1);
        points
            .iter()
            .copied()
            .filter(near)
            .step_by(stride)
            .collect()
    }

    /// The sum of [`Self::value`] over `cells` shifted by (`ix`, `iy`), a translation of the
    /// layout's window. The first `on_grid` cells stay on the grid at every such translation,
    /// so they need none of the edge rules and their values are read straight from the level.
    fn score(&self, cells: &[(i32, i32)], on_grid: usize, level: usize, ix: i32, iy: i32) -> u32 {
        let (inside, outside) = cells.split_at(on_grid);
        let values = &self.levels[level];
        let shift = iy as isize * self.width as isize + ix as isize;
        let direct: u32 = inside
            .iter()
            .map(|&(x, y)| {
                values[(y as isize * self.width as isize + x as isize + shift) as usize] as u32
            })
            .sum();
        direct
            + outside
                .iter()
                .map(|&(x, y)| self.value(level, x + ix, y + iy) as u32)
                .sum::<u32>()
    }
}

/// How a rival to the winner is looked for ([`LookupGrid::search_with_rival`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rival {
    /// Poses within this distance and this turn of the winner are the winner's own peak.
    pub exclude_m: f32,
    pub exclude_rad: f32,
    /// A rival counts from this fraction of the winner's score.
    pub ratio: f32,
}

/// The scored points' cells per heading, and what turns a candidate back into a pose.
struct Layout {
    cells: Vec<Vec<(i32, i32)>>,
    /// How many of each heading's cells, at its start, stay on the grid at every translation
    /// of the window.
    on_grid: Vec<usize>,
    headings: i32,
    heading_step: f32,
    half: i32,
    norm: f32,
    /// The motion prior's penalty in score units: per square cell of translation from the
    /// guess, and for each heading of `cells`.
    cell_cost: f32,
    turn_cost: Vec<u32>,
}

impl Layout {
    /// The least penalty of any leaf in the `size × size` block at (`ix`, `iy`) of `heading`.
    fn cost(&self, heading: usize, ix: i32, iy: i32, size: i32) -> u32 {
        // The block's nearest leaf to the guess along one axis, in cells.
        let gap = |lo: i32| (lo.max(0) + (lo + size - 1).min(0)) as f32;
        let (dx, dy) = (gap(ix), gap(iy));
        self.turn_cost[heading].saturating_add((self.cell_cost * (dx * dx + dy * dy)) as u32)
    }

    /// The leaf of `pose` (an answer of this layout).
    fn candidate_of(&self, grid: &LookupGrid, pose: Pose2, guess: Pose2) -> Candidate {
        let turn = plumbline_core::geom::normalize_angle(pose.theta - guess.theta);
        Candidate {
            heading: ((turn / self.heading_step).round() as i32 + self.headings).max(0) as usize,
            ix: ((pose.x - guess.x) / grid.resolution).round() as i32,
            iy: ((pose.y - guess.y) / grid.resolution).round() as i32,
            level: 0,
            bound: 0,
        }
    }

    fn found(&self, grid: &LookupGrid, best: Candidate, guess: Pose2) -> Found {
        let theta = guess.theta + (best.heading as i32 - self.headings) as f32 * self.heading_step;
        Found {
            pose: Pose2::new(
                guess.x + best.ix as f32 * grid.resolution,
                guess.y + best.iy as f32 * grid.resolution,
                plumbline_core::geom::normalize_angle(theta),
            ),
            // The leaf's bound is its penalised score: the penalty is added back.
            score: (best.bound + self.cost(best.heading, best.ix, best.iy, 1)) as f32 / self.norm,
        }
    }
}

/// Leaves this close to a winner are not rivals.
#[derive(Clone, Copy, Debug)]
struct Exclusion {
    around: Candidate,
    cells: i32,
    headings: i32,
}

impl Exclusion {
    fn contains(&self, c: &Candidate) -> bool {
        (c.ix - self.around.ix).abs() <= self.cells
            && (c.iy - self.around.iy).abs() <= self.cells
            && (c.heading as i32 - self.around.heading as i32).abs() <= self.headings
    }
}

#[derive(Clone, Copy, Debug)]
struct Candidate {
    heading: usize,
    ix: i32,
    iy: i32,
    level: usize,
    bound: u32,
}

struct Search<'g> {
    grid: &'g LookupGrid,
    layout: &'g Layout,
    /// Best complete score so far (starts at the acceptance threshold) and its candidate.
    best: (u32, Option<Candidate>),
    exclusion: Option<Exclusion>,
}

impl Search<'_> {
    /// Depth first, best bound first; a block is opened only if it can beat the best so far.
    fn expand(&mut self, c: Candidate) {
        if c.bound <= self.best.0 {
            return;
        }
        if c.level == 0 {
            if !self.exclusion.is_some_and(|e| e.contains(&c)) {
                self.best = (c.bound, Some(c));
            }
            return;
        }
        let level = c.level - 1;
        let step = 1i32 << level;
        let (cells, on_grid) = (
            &self.layout.cells[c.heading],
            self.layout.on_grid[c.heading],
        );
        let mut children = [c; 4];
        let mut count = 0;
        for (dx, dy) in [(0, 0), (step, 0), (0, step), (step, step)] {
            let (ix, iy) = (c.ix + dx, c.iy + dy);
            if ix > self.layout.half || iy > self.layout.half {
                continue;
            }
            let cost = self.layout.cost(c.heading, ix, iy, step);
            let bound = self
                .grid
                .score(cells, on_grid, level, ix, iy)
                .saturating_sub(cost);
            children[count] = Candidate {
                heading: c.heading,
                ix,
                iy,
                level,
                bound,
            };
            count += 1;
        }
        let children = &mut children[..count];
        children.sort_by_key(|c| std::cmp::Reverse(c.bound));
        for &child in children.iter() {
            self.expand(child);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::likelihood::{gaussian_kernel, KERNEL_CELLS};
    use super::*;

    /// An L-shaped room corner and a wall stub: enough structure to fix x, y and heading.
    fn room() -> Vec<Vec2> {
        let mut pts = Vec::new();
        for i in 0..80 {
            let s = i as f32 * 0.05;
            pts.push(Vec2::new(s - 1.0, 2.0));
            pts.push(Vec2::new(3.0, s - 1.5));
            pts.push(Vec2::new(-1.0, s * 0.5 - 1.0));
        }
        pts
    }

    #[test]
    fn finds_a_known_offset_from_a_wrong_guess() {
        let cfg = CorrelativeConfig::default();
        let reference = room();
        let truth = Pose2::new(0.4, -0.3, 0.2);
        let current: Vec<Vec2> = reference
            .iter()
            .map(|&p| truth.inverse().transform(p))
            .collect();
        let grid = LookupGrid::new(&reference, 1.0, &cfg, 6);
        let window = Window {
            translation_m: 0.8,
            heading_rad: 0.4,
        };
        let found = grid
            .search(&current, Pose2::IDENTITY, window, 0.3, &cfg)
            .expect("a pose");
        let (shift, turn) = found.pose.distance_to(truth);
        // Within a cell and a heading step (the step that moves the farthest point a cell).
        let cell = cfg.resolution_m;
        let reach = current.iter().map(|p| p.norm()).fold(0.0, f32::max);
        let step = (1.0 - cell * cell / (2.0 * reach * reach)).acos();
        assert!(shift <= 1.5 * cell && turn <= step, "{found:?}");
        assert!(found.score > 0.8, "{found:?}");
    }

    /// The room, the room as seen from `truth`, and a window that holds it.
    fn room_seen_from(truth: Pose2) -> (CorrelativeConfig, Vec<Vec2>, Vec<Vec2>, Window) {
        let reference = room();
        let current = reference
            .iter()
            .map(|&p| truth.inverse().transform(p))
            .collect();
        let window = Window {
            translation_m: 0.6,
            heading_rad: 0.35,
        };
        (CorrelativeConfig::default(), reference, current, window)
    }

    /// The grid by its definition, cell by cell: each point's kernel stamped where it lands on
    /// the grid, and each level the largest of four cells of the one below (0 past the edges).
    fn levels_by_definition(grid: &LookupGrid, points: &[Vec2], sigma_m: f32) -> Vec<Vec<u8>> {
        let (w, h) = (grid.width, grid.height);
        let kernel = gaussian_kernel(grid.resolution, sigma_m);
        let mut base = vec![0u8; (w * h) as usize];
        for p in points.iter().filter(|p| p.is_finite()) {
            let cx = ((p.x - grid.origin.x) / grid.resolution) as i32;
            let cy = ((p.y - grid.origin.y) / grid.resolution) as i32;
            for dy in -KERNEL_CELLS..=KERNEL_CELLS {
                for dx in -KERNEL_CELLS..=KERNEL_CELLS {
                    let (x, y) = (cx + dx, cy + dy);
                    if (0..w).contains(&x) && (0..h).contains(&y) {
                        let k = (dy + KERNEL_CELLS) * (2 * KERNEL_CELLS + 1) + dx + KERNEL_CELLS;
                        let cell = &mut base[(y * w + x) as usize];
                        *cell = (*cell).max(kernel[k as usize]);
                    }
                }
            }
        }
        let mut levels = vec![base];
        for k in 1..grid.levels.len() {
            let step = 1 << (k - 1);
            let prev = &levels[k - 1];
            let at = |x: i32, y: i32| {
                if x < w && y < h {
                    prev[(y * w + x) as usize]
                } else {
                    0
                }
            };
            let mut next = vec![0u8; prev.len()];
            for y in 0..h {
                for x in 0..w {
                    next[(y * w + x) as usize] = at(x, y)
                        .max(at(x + step, y))
                        .max(at(x, y + step))
                        .max(at(x + step, y + step));
                }
            }
            levels.push(next);
        }
        levels
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Every level holds the values of the definition, for points at the grid's edges (no
        /// margin), grids narrower than a block, points sharing a cell and kernels so wide
        /// that more than their centre reaches the peak.
        #[test]
        fn the_pyramid_holds_the_values_of_its_definition(
            points in proptest::collection::vec((-2.0f32..2.0, -1.0f32..1.5), 1..60),
            margin in proptest::prop_oneof![proptest::strategy::Just(0.0f32), 0.0f32..0.7],
            levels in 1usize..8,
            sigma in proptest::prop_oneof![0.05f32..0.3, 0.3f32..4.0],
        ) {
            let cfg = CorrelativeConfig { sigma_m: sigma, ..CorrelativeConfig::default() };
            // Each point with a neighbour a few millimetres off, mostly in the same cell.
            let points: Vec<Vec2> = points
                .into_iter()
                .flat_map(|(x, y)| [Vec2::new(x, y), Vec2::new(x + 0.004, y - 0.003)])
                .collect();
            let grid = LookupGrid::new(&points, margin, &cfg, levels);
            proptest::prop_assert_eq!(grid.levels.len(), levels);
            proptest::prop_assert_eq!(&grid.levels, &levels_by_definition(&grid, &points, sigma));
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// A score is the sum of every cell's value at each translation of the window and each
        /// level, for scans that reach past the grid on every side.
        #[test]
        fn a_score_is_the_sum_of_its_cells_values(
            current in proptest::collection::vec((-4.0f32..4.0, -4.0f32..4.0), 1..40),
            x in -0.5f32..0.5, y in -0.5f32..0.5, t in -0.3f32..0.3,
            translation_m in 0.0f32..1.2, levels in 1usize..6,
        ) {
            let cfg = CorrelativeConfig::default();
            let grid = LookupGrid::new(&room(), 0.3, &cfg, levels);
            let current: Vec<Vec2> = current.into_iter().map(|(x, y)| Vec2::new(x, y)).collect();
            let window = Window { translation_m, heading_rad: 0.1 };
            let prior = MotionPrior::default();
            let layout = grid.layout(&current, Pose2::new(x, y, t), window, prior, &cfg).unwrap();
            let half = layout.half;
            for (cells, &on_grid) in layout.cells.iter().zip(&layout.on_grid) {
                for level in 0..levels {
                    for ix in (-half..=half).step_by(3) {
                        for iy in (-half..=half).step_by(2) {
                            let sum: u32 = cells
                                .iter()
                                .map(|&(x, y)| u32::from(grid.value(level, x + ix, y + iy)))
                                .sum();
                            proptest::prop_assert_eq!(grid.score(cells, on_grid, level, ix, iy), sum);
                        }
                    }
                }
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Pruning never loses the best fine-grid pose, wherever the truth lies in the window
        /// (blocks hanging over the grid's edges included).
        #[test]
        fn branch_and_bound_equals_exhaustive_search(
            x in -0.5f32..0.5, y in -0.5f32..0.5, t in -0.3f32..0.3, levels in 2usize..7,
        ) {
            let (cfg, reference, current, window) = room_seen_from(Pose2::new(x, y, t));
            let pruned = LookupGrid::new(&reference, 0.2, &cfg, levels)
                .search(&current, Pose2::IDENTITY, window, 0.0, &cfg);
            let exhaustive = LookupGrid::new(&reference, 0.2, &cfg, 1)
                .search(&current, Pose2::IDENTITY, window, 0.0, &cfg);
            proptest::prop_assert_eq!(pruned.map(|f| f.score), exhaustive.map(|f| f.score));
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// With a motion prior too, pruning never loses the best penalised pose, and the score
        /// returned is the pose's own fit. Poses whose penalised scores tie may differ: which
        /// of them wins depends on the order blocks are opened in.
        #[test]
        fn branch_and_bound_with_a_prior_equals_exhaustive_search(
            x in -0.5f32..0.5, y in -0.5f32..0.5, t in -0.3f32..0.3, levels in 2usize..7,
            per_m2 in 0.0f32..5.0, per_rad2 in 0.0f32..2.0,
        ) {
            let (cfg, reference, current, window) = room_seen_from(Pose2::new(x, y, t));
            let prior = MotionPrior { per_m2, per_rad2 };
            let guess = Pose2::new(0.1, -0.1, 0.05);
            let pruned_grid = LookupGrid::new(&reference, 0.2, &cfg, levels);
            let grid = LookupGrid::new(&reference, 0.2, &cfg, 1);
            let best_penalised = |grid: &LookupGrid| {
                let layout = grid.layout(&current, guess, window, prior, &cfg).unwrap();
                grid.run(&layout, 0, None).map(|c| c.bound)
            };
            proptest::prop_assert_eq!(best_penalised(&pruned_grid), best_penalised(&grid));
            let found = pruned_grid
                .search_near(&current, guess, window, prior, 0.0, &cfg)
                .unwrap();
            let own = grid.score_pose(&current, found.pose, &cfg);
            proptest::prop_assert!((own - found.score).abs() < 1e-3, "{own} vs {found:?}");
        }
    }

    #[test]
    fn along_a_featureless_corridor_the_prior_keeps_the_guess() {
        let cfg = CorrelativeConfig::default();
        // Two walls 2 m apart, 20 m long; the scan moved 0.7 m along them.
        let reference: Vec<Vec2> = (0..400)
            .flat_map(|i| {
                let x = i as f32 * 0.05 - 10.0;
                [Vec2::new(x, 1.0), Vec2::new(x, -1.0)]
            })
            .collect();
        let truth = Pose2::new(0.7, 0.0, 0.0);
        let current: Vec<Vec2> = reference
            .iter()
            .filter(|p| p.x.abs() < 6.0)
            .map(|&p| truth.inverse().transform(p))
            .collect();
        let grid = LookupGrid::new(&reference, 1.0, &cfg, 5);
        let window = Window {
            translation_m: 1.5,
            heading_rad: 0.3,
        };
        // The guess is right along the corridor and off across it and in heading.
        let guess = Pose2::new(0.7, 0.25, 0.04);
        let prior = MotionPrior {
            per_m2: 0.5,
            per_rad2: 0.5,
        };
        let found = grid
            .search_near(&current, guess, window, prior, 0.3, &cfg)
            .expect("a pose");
        let (shift, turn) = found.pose.distance_to(truth);
        assert!(shift <= 1.5 * cfg.resolution_m && turn < 0.02, "{found:?}");
        assert!(found.score > 0.8, "{found:?}");
    }

    #[test]
    fn nothing_above_the_threshold_is_none_and_empty_input_is_none() {
        let cfg = CorrelativeConfig::default();
        let grid = LookupGrid::new(&room(), 1.0, &cfg, 4);
        let far: Vec<Vec2> = (0..50).map(|i| Vec2::new(40.0, i as f32)).collect();
        let w = Window {
            translation_m: 0.2,
            heading_rad: 0.05,
        };
        assert!(grid.search(&far, Pose2::IDENTITY, w, 0.2, &cfg).is_none());
        assert!(grid.search(&[], Pose2::IDENTITY, w, 0.0, &cfg).is_none());
        let empty = LookupGrid::new(&[], 0.5, &cfg, 3);
        assert!(empty
            .search(&room(), Pose2::IDENTITY, w, 0.1, &cfg)
            .is_none());
    }
}
