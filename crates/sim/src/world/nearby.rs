//! The walls around a short-range sensor, sorted by the direction they lie in, so that each beam
//! tests only the few walls it can reach.
//!
//! Why: a lidar casts one or two beams per physics step from a pose that has moved millimetres
//! since the last, and [`Scene::cast`]'s grid walk starts from scratch for every beam. Here the
//! walls within the sensor's reach are gathered once, around a centre, into angular sectors
//! (seen from the centre); they are gathered again only when the sensor has left a small disc
//! around that centre. A wall is listed in every sector a beam from anywhere in the disc could
//! meet it in, so the result is exactly the grid's: the same walls are tested by the same
//! `hit_segment`. Where the lists would be long (a rasterised building of thousands of short
//! walls, or a 30 m lidar among hundreds of walls), the grid is faster and is used instead.
//!
//! Directions are binned by a pseudo-angle (a monotone, division-only stand-in for `atan2`),
//! which is what makes the per-beam look-up cheap. Each sector lists its walls nearest first,
//! so a beam stops at the first wall that cannot be beaten: the one-cell-at-a-time early exit
//! of the grid walk, which is what keeps long-range (30 m) beams cheap.

use crate::math::Vec3;
use crate::world::scene::{hit_segment, wall_hit, Cylinder, Hit, Scene};
use crate::world::Segment;
use core::f64::consts::{PI, TAU};

/// How far the sensor may move from where the walls were gathered before they are gathered
/// again, m. Larger means fewer gatherings but wider sectors for near walls.
const SLACK_M: f64 = 0.15;
/// Angular sectors around the centre.
const SECTORS: usize = 64;
/// Above this many walls within reach the scene's grid is used instead (gathering them would
/// cost more than it saves).
const MAX_WALLS: usize = 400;
/// Above this many walls per sector on average the grid is used instead: a long beam then
/// passes more listed walls before its hit than grid cells (200 walls within 30 m: 9 per
/// sector, and the grid walk is about twice as fast).
const MAX_PER_SECTOR: usize = 4;
/// Angular padding for the rounding of `atan2`, `sin` and `cos`, rad.
const PAD_RAD: f64 = 1e-9;

/// A monotone map of the direction of (x, y) onto [0, 4): 0 along +x, 1 along +y, 2 along -x,
/// 3 along -y. (x, y) must not be (0, 0).
fn pseudo_angle(x: f64, y: f64) -> f64 {
    let p = y / (x.abs() + y.abs());
    if x < 0.0 {
        2.0 - p
    } else if y < 0.0 {
        4.0 + p
    } else {
        p
    }
}

/// Converted through `u32`: the value is below 64, and x86-64's SSE2 has no conversion to an
/// unsigned 64-bit integer, so a saturating `as usize` costs about 15 instructions per beam
/// against about 6 (same result).
fn sector_of(x: f64, y: f64) -> usize {
    ((pseudo_angle(x, y) * (SECTORS as f64 / 4.0)) as u32 as usize).min(SECTORS - 1)
}

/// Walls within reach of a sensor, binned by direction.
#[derive(Clone, Debug)]
pub struct Nearby {
    reach_m: f64,
    /// Where the walls were gathered; `None` before the first cast.
    center: Option<[f64; 2]>,
    /// Too many walls within reach: cast through the grid.
    use_grid: bool,
    /// The walls within reach and their distance from the centre, nearest first.
    walls: Vec<(f64, Segment)>,
    /// Walls of sector k are `walls[items[starts[k]..starts[k + 1]]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Scratch: wall indices from the scene, and sector spans per wall.
    ids: Vec<u32>,
    spans: Vec<(usize, usize)>,
}

/// Rounding allowance of the early exit, m.
const EXIT_PAD_M: f64 = 1e-9;

impl Nearby {
    /// For a sensor whose beams reach at most `reach_m` (its maximum range).
    pub fn new(reach_m: f64) -> Self {
        Self {
            reach_m,
            center: None,
            use_grid: false,
            walls: Vec::new(),
            starts: Vec::new(),
            items: Vec::new(),
            ids: Vec::new(),
            spans: Vec::new(),
        }
    }

    /// [`Scene::cast`] for a ray of at most the reach given at construction.
    #[inline]
    pub fn cast(
        &mut self,
        scene: &Scene,
        o: Vec3,
        d: Vec3,
        max_range_m: f64,
        people: &[Cylinder],
    ) -> Option<Hit> {
        let max_range_m = max_range_m.min(self.reach_m);
        self.cover(scene, [o.x, o.y]);
        if self.use_grid {
            return scene.cast(o, d, max_range_m, people);
        }
        let bound = scene.cast_open(o, d, max_range_m, people);
        if d.x == 0.0 && d.y == 0.0 {
            // Straight up or down: parallel to every wall.
            return bound;
        }
        let mut best_t = bound.map_or(max_range_m, |h| h.range_m);
        let mut best = None;
        let k = sector_of(d.x, d.y);
        for &i in &self.items[self.starts[k] as usize..self.starts[k + 1] as usize] {
            let (near, wall) = &self.walls[i as usize];
            // The origin is within SLACK_M of the centre, so this wall and all after it are at
            // least near - SLACK_M away along any ray.
            if near - SLACK_M - EXIT_PAD_M >= best_t {
                break;
            }
            if let Some(t) = hit_segment(o, d, wall) {
                if t < best_t {
                    best_t = t;
                    best = Some(wall);
                }
            }
        }
        best.map(|w| wall_hit(w, d, best_t)).or(bound)
    }

    /// Gathers the walls again if `p` has left the disc they were gathered for. The check runs
    /// for every beam and is inlined; the gathering, about once per 0.15 m flown, is not.
    #[inline(always)]
    fn cover(&mut self, scene: &Scene, p: [f64; 2]) {
        if let Some(c) = self.center {
            let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
            if dx * dx + dy * dy <= SLACK_M * SLACK_M {
                return;
            }
        }
        self.gather(scene, p);
    }

    #[inline(never)]
    fn gather(&mut self, scene: &Scene, p: [f64; 2]) {
        self.center = Some(p);
        scene.walls_near(p, self.reach_m + SLACK_M, &mut self.ids);
        self.use_grid = self.ids.len() > MAX_WALLS;
        if self.use_grid {
            return;
        }
        self.walls.clear();
        self.walls.extend(self.ids.iter().map(|&i| {
            let w = scene.walls()[i as usize];
            (w.distance(p), w)
        }));
        self.walls.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.spans.clear();
        self.spans
            .extend(self.walls.iter().map(|(near, w)| sectors_seen(w, *near, p)));
        // Counting sort of (sector, wall) pairs into the compressed lists.
        let mut counts = [0u32; SECTORS];
        for &(first, n) in &self.spans {
            for j in 0..n {
                counts[(first + j) % SECTORS] += 1;
            }
        }
        self.starts.clear();
        self.starts.push(0);
        for c in counts {
            let last = self.starts[self.starts.len() - 1];
            self.starts.push(last + c);
        }
        if self.starts[SECTORS] as usize > MAX_PER_SECTOR * SECTORS {
            self.use_grid = true;
            return;
        }
        self.items.clear();
        self.items.resize(self.starts[SECTORS] as usize, 0);
        let mut fill = [0u32; SECTORS];
        fill.copy_from_slice(&self.starts[..SECTORS]);
        for (w, &(first, n)) in self.spans.iter().enumerate() {
            for j in 0..n {
                let k = (first + j) % SECTORS;
                self.items[fill[k] as usize] = w as u32;
                fill[k] += 1;
            }
        }
    }
}

/// The sectors (first, count) in which a beam from within `SLACK_M` of `c` can meet wall `w`,
/// `near` away from `c`.
fn sectors_seen(w: &Segment, near: f64, c: [f64; 2]) -> (usize, usize) {
    let all = (0, SECTORS);
    if near <= SLACK_M {
        return all;
    }
    // The wall as seen from the centre spans less than half a turn (it does not pass through
    // the centre); seen from a point up to SLACK_M away, each direction can turn by at most
    // asin(SLACK_M / distance).
    let angle = |q: [f64; 2]| (q[1] - c[1]).atan2(q[0] - c[0]);
    let (ta, tb) = (angle(w.a), angle(w.b));
    let ccw = (tb - ta).rem_euclid(TAU);
    let (from, span) = if ccw <= PI {
        (ta, ccw)
    } else {
        (tb, TAU - ccw)
    };
    let widen = (SLACK_M / near).asin() + PAD_RAD;
    let (lo, hi) = (from - widen, from + span + widen);
    // Sectors are equal in pseudo-angle, up to 8 / SECTORS rad wide in angle: keep two of
    // them clear so that the first and last sector of a long arc cannot coincide.
    if hi - lo >= TAU - 16.0 / SECTORS as f64 {
        return all;
    }
    let first = sector_of(lo.cos(), lo.sin());
    let last = sector_of(hi.cos(), hi.sin());
    (first, (last + SECTORS - first) % SECTORS + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::World;
    use proptest::prelude::*;

    #[test]
    fn pseudo_angle_is_monotone_around_the_circle() {
        let mut last = -1.0;
        for k in 0..3600 {
            let a = k as f64 / 3600.0 * TAU;
            let p = pseudo_angle(a.cos(), a.sin());
            assert!(p > last && (0.0..4.0).contains(&p), "{a}: {p}");
            last = p;
        }
    }

    fn office() -> (World, Scene) {
        let w = World::shipped("office").unwrap().unwrap();
        let s = Scene::new(&w);
        (w, s)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// A sensor wandering through the office, beams in every direction and tilt: every
        /// range equals the grid's to the bit.
        #[test]
        fn agrees_with_the_grid_to_the_bit(
            x0 in 0.5f64..19.5, y0 in 0.5f64..9.5, z in 0.2f64..2.5,
            steps in prop::collection::vec((-0.08f64..0.08, -0.08f64..0.08), 1..40),
            yaw0 in -3.2f64..3.2, tilt in -0.4f64..0.4,
            reach in prop::sample::select(vec![4.0, 30.0]),
        ) {
            let (_, scene) = office();
            let mut near = Nearby::new(reach);
            let (mut x, mut y, mut yaw) = (x0, y0, yaw0);
            for (dx, dy) in steps {
                x = (x + dx).clamp(0.01, 19.99);
                y = (y + dy).clamp(0.01, 9.99);
                yaw += 0.37;
                let o = Vec3::new(x, y, z);
                let d = Vec3::new(tilt.cos() * yaw.cos(), tilt.cos() * yaw.sin(), tilt.sin());
                let want = scene.cast(o, d, reach, &[]).map(|h| h.range_m);
                let got = near.cast(&scene, o, d, reach, &[]).map(|h| h.range_m);
                prop_assert_eq!(got, want, "from {:?} along {:?}", o, d);
            }
        }
    }

    #[test]
    fn the_early_exit_allows_for_the_sensor_having_moved() {
        // Walls gathered around (0, 0); the sensor then moves 0.14 m toward the wall at x = 1
        // and casts a beam tilted down, which meets the floor at 0.95 m but the wall first, at
        // 0.86 m horizontally: closer than the wall's 1 m from where the walls were gathered.
        let w = World::parse("start 0 0 0\nceiling 2.5\noutline -5 -5 1 -5 1 5 -5 5\n").unwrap();
        let scene = Scene::new(&w);
        let mut near = Nearby::new(4.0);
        let tilt: f64 = 0.3;
        let z = 0.95 * tilt.sin();
        let d = Vec3::new(tilt.cos(), 0.0, -tilt.sin());
        near.cast(&scene, Vec3::new(0.0, 0.0, z), d, 4.0, &[]);
        let o = Vec3::new(0.14, 0.0, z);
        let hit = near.cast(&scene, o, d, 4.0, &[]).unwrap();
        assert!((hit.range_m - 0.86 / tilt.cos()).abs() < 1e-12, "{hit:?}");
        assert_eq!(Some(hit), scene.cast(o, d, 4.0, &[]));
    }

    #[test]
    fn dense_worlds_fall_back_to_the_grid() {
        // Thousands of walls within reach (a rasterised building at 30 m).
        let w = World::shipped("intel").unwrap().unwrap();
        let scene = Scene::new(&w);
        let mut near = Nearby::new(30.0);
        let o = Vec3::new(w.start[0], w.start[1], 1.0);
        let d = Vec3::new(1.0, 0.0, 0.0);
        let got = near.cast(&scene, o, d, 30.0, &[]);
        assert!(near.use_grid);
        assert_eq!(got, scene.cast(o, d, 30.0, &[]));
        // A hundred small rooms, 200 walls all within 30 m: too many per sector (inside an
        // outline, as a world must enclose its start).
        let mut text = String::from("start 2 2 0\noutline -1 -1 41 -1 41 41 -1 41\n");
        for i in 0..10 {
            for j in 0..10 {
                let (x, y) = (i as f64 * 4.0, j as f64 * 4.0);
                text += &format!(
                    "wall {x} {y} {} {y}\nwall {x} {y} {x} {}\n",
                    x + 3.0,
                    y + 3.0
                );
            }
        }
        let rooms = Scene::new(&World::parse(&text).unwrap());
        let mut near = Nearby::new(30.0);
        near.cast(&rooms, Vec3::new(18.0, 18.0, 1.0), d, 30.0, &[]);
        assert!(near.use_grid);
        // The office at the XV-11's 4 m keeps its sectors (what the property test exercises).
        let (_, office) = office();
        let mut near = Nearby::new(4.0);
        near.cast(&office, Vec3::new(7.5, 5.0, 1.0), d, 4.0, &[]);
        assert!(!near.use_grid);
    }
}
