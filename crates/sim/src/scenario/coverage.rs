//! How much of a world an exploration has seen, measured against the world's truth.
//!
//! The area that counts is what the vehicle could reach from the start: the places its centre
//! can get to (flood fill over cells at least its radius from every wall and outside blocks)
//! grown by its radius, i.e. every point its body can cover. Space behind a gap narrower than
//! the vehicle is not part of it: no guidance could be asked to explore it. A cell is seen
//! when a lidar beam from the true pose passes over it within the lidar's range before meeting
//! a wall (people are ignored here: they hide a room only for a moment).

use crate::math::Vec3;
use crate::sensors::lidar::LidarScan;
use crate::world::scene::Scene;
use crate::world::World;

/// Raster cell size, m: fine enough that a 1.2 m door and a 0.7 m vehicle are many cells.
pub const COVERAGE_CELL_M: f64 = 0.1;

/// The reachable area of a world and what of it has been seen so far.
pub struct Coverage {
    scene: Scene,
    origin: [f64; 2],
    nx: usize,
    ny: usize,
    /// Cell is part of the reachable area.
    area: Vec<bool>,
    seen: Vec<bool>,
    area_cells: usize,
    seen_cells: usize,
    /// (time, explored fraction) after each revolution.
    series: Vec<(f64, f64)>,
}

impl Coverage {
    /// The area a vehicle of `radius_m` can reach from the world's start.
    pub fn new(world: &World, radius_m: f64) -> Self {
        let [x0, y0, x1, y1] = world.bounds();
        let pad = 2.0 * COVERAGE_CELL_M;
        let origin = [x0 - pad, y0 - pad];
        let nx = ((x1 - x0 + 2.0 * pad) / COVERAGE_CELL_M).ceil() as usize;
        let ny = ((y1 - y0 + 2.0 * pad) / COVERAGE_CELL_M).ceil() as usize;
        let scene = Scene::new(world);
        let mut c = Self {
            scene,
            origin,
            nx,
            ny,
            area: vec![false; nx * ny],
            seen: vec![false; nx * ny],
            area_cells: 0,
            seen_cells: 0,
            series: Vec::new(),
        };
        let centres = c.reachable_centres(world, radius_m);
        c.grow_into_area(&centres, radius_m);
        c.area_cells = c.area.iter().filter(|&&a| a).count();
        c
    }

    fn centre(&self, i: usize) -> [f64; 2] {
        [
            self.origin[0] + ((i % self.nx) as f64 + 0.5) * COVERAGE_CELL_M,
            self.origin[1] + ((i / self.nx) as f64 + 0.5) * COVERAGE_CELL_M,
        ]
    }

    fn cell_of(&self, p: [f64; 2]) -> Option<usize> {
        let cx = ((p[0] - self.origin[0]) / COVERAGE_CELL_M).floor();
        let cy = ((p[1] - self.origin[1]) / COVERAGE_CELL_M).floor();
        let inside = cx >= 0.0 && cy >= 0.0 && cx < self.nx as f64 && cy < self.ny as f64;
        inside.then(|| cy as usize * self.nx + cx as usize)
    }

    /// Cells where the vehicle's centre fits, connected to the start (4-neighbours: two cells
    /// a wall runs between are never both at the vehicle's radius from it).
    fn reachable_centres(&self, world: &World, radius_m: f64) -> Vec<bool> {
        let fits = |p: [f64; 2]| {
            self.scene.clearance(p, radius_m + COVERAGE_CELL_M) >= radius_m
                && !world.inside_block(p)
        };
        let mut reached = vec![false; self.nx * self.ny];
        let Some(start) = self.cell_of([world.start[0], world.start[1]]) else {
            return reached;
        };
        // The start itself is checked free before any flight; its cell centre may lie a few
        // centimetres closer to a wall, so it seeds the fill regardless.
        let mut stack = vec![start];
        reached[start] = true;
        while let Some(i) = stack.pop() {
            let (x, y) = (i % self.nx, i / self.nx);
            let neighbours = [
                (x > 0).then(|| i - 1),
                (x + 1 < self.nx).then(|| i + 1),
                (y > 0).then(|| i - self.nx),
                (y + 1 < self.ny).then(|| i + self.nx),
            ];
            for n in neighbours.into_iter().flatten() {
                if !reached[n] && fits(self.centre(n)) {
                    reached[n] = true;
                    stack.push(n);
                }
            }
        }
        reached
    }

    /// The area: every cell within `radius_m` of a reachable centre. A reachable centre has no
    /// wall within the radius, so the disc never reaches through one.
    fn grow_into_area(&mut self, centres: &[bool], radius_m: f64) {
        let r = (radius_m / COVERAGE_CELL_M).floor() as isize;
        let r2 = (radius_m / COVERAGE_CELL_M).powi(2);
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let inner = |i: usize| {
            let (x, y) = ((i % self.nx) as isize, (i / self.nx) as isize);
            [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().all(|(dx, dy)| {
                let (a, b) = (x + dx, y + dy);
                a >= 0 && b >= 0 && a < nx && b < ny && centres[(b * nx + a) as usize]
            })
        };
        for (i, _) in centres.iter().enumerate().filter(|(_, &c)| c) {
            self.area[i] = true;
            // Discs of inner cells are covered by their neighbours' discs but for the centre.
            if inner(i) {
                continue;
            }
            let (x, y) = ((i % self.nx) as isize, (i / self.nx) as isize);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (a, b) = (x + dx, y + dy);
                    if ((dx * dx + dy * dy) as f64) < r2 && a >= 0 && b >= 0 && a < nx && b < ny {
                        self.area[(b * nx + a) as usize] = true;
                    }
                }
            }
        }
    }

    /// Marks what the revolution `scan` saw from the true position `position` and heading
    /// `yaw_rad` (the scan plane taken as level).
    pub fn observe(&mut self, scan: &LidarScan, position: Vec3, yaw_rad: f64) {
        let z = position.z.clamp(0.05, self.scene.ceiling_m() - 0.05);
        let o = Vec3::new(position.x, position.y, z);
        for k in 0..scan.ranges_m.len() {
            let a = yaw_rad + scan.start_angle_rad + scan.increment_rad * k as f64;
            let d = Vec3::new(a.cos(), a.sin(), 0.0);
            let reach = self
                .scene
                .wall_range(o, d, scan.max_range_m)
                .unwrap_or(scan.max_range_m);
            self.mark_ray([o.x, o.y], [d.x, d.y], reach);
        }
        self.series.push((scan.stamp_s, self.fraction()));
    }

    /// Marks every cell the ray from `p` along unit `d` crosses within `reach` (grid traversal
    /// of Amanatides and Woo: each crossed cell once, none skipped).
    fn mark_ray(&mut self, p: [f64; 2], d: [f64; 2], reach: f64) {
        let Some(mut i) = self.cell_of(p) else { return };
        let rel = [
            (p[0] - self.origin[0]) / COVERAGE_CELL_M,
            (p[1] - self.origin[1]) / COVERAGE_CELL_M,
        ];
        let cell = [rel[0].floor() as isize, rel[1].floor() as isize];
        let step = [d[0].signum() as isize, d[1].signum() as isize];
        let axis_next = |r: f64, c: isize, s: isize, dir: f64| {
            if dir == 0.0 {
                f64::INFINITY
            } else {
                let edge = if s > 0 { (c + 1) as f64 } else { c as f64 };
                (edge - r) * COVERAGE_CELL_M / dir
            }
        };
        let (mut tx, mut ty) = (
            axis_next(rel[0], cell[0], step[0], d[0]),
            axis_next(rel[1], cell[1], step[1], d[1]),
        );
        // Infinite along an axis the ray does not move on. Kept in locals rather than arrays
        // indexed by the axis: through memory each step would wait on the store of the last.
        let (dx, dy) = (COVERAGE_CELL_M / d[0].abs(), COVERAGE_CELL_M / d[1].abs());
        let (mut cx, mut cy) = (cell[0], cell[1]);
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        loop {
            self.mark(i);
            if ty < tx {
                if ty > reach {
                    return;
                }
                ty += dy;
                cy += step[1];
                if cy < 0 || cy >= ny {
                    return;
                }
            } else {
                if tx > reach {
                    return;
                }
                tx += dx;
                cx += step[0];
                if cx < 0 || cx >= nx {
                    return;
                }
            }
            i = (cy * nx + cx) as usize;
        }
    }

    fn mark(&mut self, i: usize) {
        if !self.seen[i] {
            self.seen[i] = true;
            self.seen_cells += usize::from(self.area[i]);
        }
    }

    /// Reachable area, m².
    pub fn area_m2(&self) -> f64 {
        self.area_cells as f64 * COVERAGE_CELL_M * COVERAGE_CELL_M
    }

    /// Share of the reachable area seen so far, 0..1.
    pub fn fraction(&self) -> f64 {
        if self.area_cells == 0 {
            return 0.0;
        }
        self.seen_cells as f64 / self.area_cells as f64
    }

    /// The explored fraction after each revolution: (time, fraction).
    pub fn series(&self) -> &[(f64, f64)] {
        &self.series
    }

    /// The first time the explored fraction reached `fraction`, s.
    pub fn time_to(&self, fraction: f64) -> Option<f64> {
        self.series.iter().find(|s| s.1 >= fraction).map(|s| s.0)
    }

    /// Whether the point lies in the reachable area.
    pub fn in_area(&self, p: [f64; 2]) -> bool {
        self.cell_of(p).is_some_and(|i| self.area[i])
    }

    /// Whether the point has been seen.
    pub fn seen(&self, p: [f64; 2]) -> bool {
        self.cell_of(p).is_some_and(|i| self.seen[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_all_round(max_range_m: f64) -> LidarScan {
        let beams = 720;
        LidarScan {
            stamp_s: 1.0,
            start_angle_rad: 0.0,
            increment_rad: std::f64::consts::TAU / beams as f64,
            max_range_m,
            beam_dt_s: 0.0,
            ranges_m: vec![1.0; beams],
            valid: vec![true; beams],
        }
    }

    #[test]
    fn a_closed_room_is_its_floor_minus_nothing_and_one_scan_sees_it_all() {
        let w = World::parse("start 2 1.5 0\noutline 0 0 4 0 4 3 0 3\n").unwrap();
        let mut c = Coverage::new(&w, 0.35);
        // The body reaches every wall; only the corners (out of a disc's reach) are left out.
        let a = c.area_m2();
        assert!(a > 11.8 && a <= 12.0, "{a}");
        c.observe(&scan_all_round(10.0), Vec3::new(2.0, 1.5, 1.0), 0.0);
        assert!(c.fraction() > 0.999, "{}", c.fraction());
        assert_eq!(c.time_to(0.9), Some(1.0));
    }

    #[test]
    fn range_limits_what_is_seen() {
        let w = World::parse("start 1 1 0\noutline 0 0 20 0 20 2 0 2\n").unwrap();
        let mut c = Coverage::new(&w, 0.35);
        c.observe(&scan_all_round(4.0), Vec3::new(1.0, 1.0, 1.0), 0.0);
        assert!(c.seen([4.5, 1.0]) && !c.seen([5.5, 1.0]));
        let f = c.fraction();
        assert!((0.2..0.3).contains(&f), "about 5 of 20 m: {f}");
    }

    #[test]
    fn walls_block_the_view_and_narrow_gaps_the_area() {
        // Two rooms joined by a 0.5 m gap: a 0.7 m vehicle cannot pass, so the second room is
        // not part of the area, and the wall between hides most of it from the first.
        let text = "start 1 1 0\noutline 0 0 8 0 8 3 0 3\nwall 4 0 4 1.25\nwall 4 1.75 4 3\n";
        let w = World::parse(text).unwrap();
        let mut c = Coverage::new(&w, 0.35);
        assert!(c.in_area([3.8, 2.0]) && !c.in_area([4.5, 2.0]) && !c.in_area([7.0, 1.0]));
        c.observe(&scan_all_round(10.0), Vec3::new(1.0, 1.0, 1.0), 0.0);
        assert!(!c.seen([6.0, 2.8]));
        assert!(c.fraction() > 0.99);
        // A vehicle small enough for the gap reaches the second room.
        let small = Coverage::new(&w, 0.2);
        assert!(small.in_area([7.0, 1.0]));
    }

    #[test]
    fn blocks_are_not_area() {
        let w = World::parse("start 1 1 0\noutline 0 0 6 0 6 6 0 6\nbox 2 2 4 4\n").unwrap();
        let c = Coverage::new(&w, 0.35);
        assert!(!c.in_area([3.0, 3.0]) && c.in_area([1.0, 5.0]));
    }
}
