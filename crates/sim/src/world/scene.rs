//! 3-D ray casting against a world: walls extruded floor to ceiling, the floor, the ceiling and
//! walking people (vertical cylinders).
//!
//! Walls are bucketed in a uniform 2-D grid; a ray walks the grid cells its floor projection
//! crosses (Amanatides and Woo's traversal) and tests only the walls listed there, so the cost
//! grows with the cells crossed rather than with the number of walls. The floor and ceiling
//! bound the ray first: a tilted scan plane that meets the floor at 3 m never looks further.

use crate::math::Vec3;
use crate::world::{Segment, World};

/// A person (or any vertical cylinder) the rays can hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    pub center: [f64; 2],
    pub radius_m: f64,
    pub height_m: f64,
}

/// What a ray met.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, m.
    pub range_m: f64,
    /// Cosine of the angle between the ray and the surface normal (1 = head-on).
    pub cos_incidence: f64,
}

/// A world prepared for ray casting.
#[derive(Clone, Debug)]
pub struct Scene {
    walls: Vec<Segment>,
    ceiling_m: f64,
    origin: [f64; 2],
    cell_m: f64,
    nx: usize,
    ny: usize,
    /// Compressed lists: walls of cell c are `items[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// `edges[k]` is wall `items[k]`, laid out in cell order for the ray walk.
    edges: Vec<Edge>,
}

impl Scene {
    /// Builds the grid. The cell edge follows the wall density, about two walls' worth of
    /// area per cell, between 0.25 m and 2 m: sparse rooms take few long steps, a rasterised
    /// building with thousands of short walls gets small cells with few walls each.
    pub fn new(world: &World) -> Self {
        let [x0, y0, x1, y1] = world.bounds();
        let area = ((x1 - x0) * (y1 - y0)).max(1.0);
        let cell = (2.0 * area / world.walls.len().max(1) as f64)
            .sqrt()
            .clamp(0.25, 2.0);
        let origin = [x0 - cell, y0 - cell];
        let nx = (((x1 - origin[0]) / cell).ceil() as usize + 1).max(1);
        let ny = (((y1 - origin[1]) / cell).ceil() as usize + 1).max(1);
        let cell_of = |v: f64, o: f64, n: usize| (((v - o) / cell).max(0.0) as usize).min(n - 1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for (i, s) in world.walls.iter().enumerate() {
            let (cx0, cx1) = (
                cell_of(s.a[0].min(s.b[0]), origin[0], nx),
                cell_of(s.a[0].max(s.b[0]), origin[0], nx),
            );
            let (cy0, cy1) = (
                cell_of(s.a[1].min(s.b[1]), origin[1], ny),
                cell_of(s.a[1].max(s.b[1]), origin[1], ny),
            );
            for cy in cy0..=cy1 {
                for cx in cx0..=cx1 {
                    let lo = [origin[0] + cx as f64 * cell, origin[1] + cy as f64 * cell];
                    if segment_touches_box(s, lo, cell) {
                        lists[cy * nx + cx].push(i as u32);
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        starts.push(0);
        for l in &lists {
            items.extend_from_slice(l);
            starts.push(items.len() as u32);
        }
        let edges = items
            .iter()
            .map(|&i| Edge::of(&world.walls[i as usize]))
            .collect();
        Self {
            walls: world.walls.clone(),
            ceiling_m: world.ceiling_m,
            origin,
            cell_m: cell,
            nx,
            ny,
            starts,
            items,
            edges,
        }
    }

    pub fn ceiling_m(&self) -> f64 {
        self.ceiling_m
    }

    /// Casts a ray from `o` along the unit vector `d`, up to `max_range_m`; `None` if nothing
    /// is closer.
    pub fn cast(&self, o: Vec3, d: Vec3, max_range_m: f64, people: &[Cylinder]) -> Option<Hit> {
        let bound = self.cast_open(o, d, max_range_m, people);
        let limit = bound.map_or(max_range_m, |h| h.range_m);
        self.cast_walls(o, d, limit).or(bound)
    }

    /// The floor, the ceiling and the people: what a ray meets before `max_range_m` besides
    /// walls. The result bounds the wall search.
    #[inline]
    pub(crate) fn cast_open(
        &self,
        o: Vec3,
        d: Vec3,
        max_range_m: f64,
        people: &[Cylinder],
    ) -> Option<Hit> {
        let mut best = None;
        let mut limit = max_range_m;
        let plane_t = if d.z < 0.0 {
            -o.z / d.z
        } else if d.z > 0.0 {
            (self.ceiling_m - o.z) / d.z
        } else {
            f64::INFINITY
        };
        if plane_t >= 0.0 && plane_t < limit {
            limit = plane_t;
            best = Some(Hit {
                range_m: plane_t,
                cos_incidence: d.z.abs(),
            });
        }
        for c in people {
            if let Some(t) = hit_cylinder(o, d, c) {
                if t < limit {
                    limit = t;
                    best = Some(Hit {
                        range_m: t,
                        cos_incidence: 1.0,
                    });
                }
            }
        }
        best
    }

    /// The nearest wall closer than `limit` along the ray, walking the grid.
    fn cast_walls(&self, o: Vec3, d: Vec3, limit: f64) -> Option<Hit> {
        self.nearest_wall(o, d, limit)
            .map(|(k, t)| self.edges[k].hit(d, t))
    }

    /// The distance along the ray to the nearest wall closer than `limit`: [`Scene::cast`]'s
    /// range for a level ray (which meets neither floor nor ceiling) among no people, without
    /// the angle of incidence.
    pub(crate) fn wall_range(&self, o: Vec3, d: Vec3, limit: f64) -> Option<f64> {
        self.nearest_wall(o, d, limit).map(|(_, t)| t)
    }

    /// The nearest wall closer than `limit` along the ray (as its place in `edges`) and its
    /// distance, walking the grid.
    #[inline(always)]
    fn nearest_wall(&self, o: Vec3, d: Vec3, limit: f64) -> Option<(usize, f64)> {
        let cell = self.cell_m;
        let (gx, gy) = ((o.x - self.origin[0]) / cell, (o.y - self.origin[1]) / cell);
        let (w, h) = (self.nx as f64, self.ny as f64);
        // A ray from inside the grid (every sensor's) walks from its own cell until it leaves
        // the grid; one from outside is first clipped to the grid rectangle (slab test). The
        // grid's border cells hold no walls, so the inside walk ending one cell later, where
        // rounding puts the exit, changes nothing.
        let inside = gx >= 0.0 && gy >= 0.0 && gx < w && gy < h;
        let (start, t1) = if inside {
            ([gx, gy], limit)
        } else {
            let (mut t0, mut t1) = (0.0f64, limit);
            for (p, v, n) in [(gx, d.x / cell, w), (gy, d.y / cell, h)] {
                if v == 0.0 {
                    if p < 0.0 || p >= n {
                        return None;
                    }
                } else {
                    let (a, b) = ((0.0 - p) / v, (n - p) / v);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            if t0 > t1 {
                return None;
            }
            ([gx + d.x / cell * t0, gy + d.y / cell * t0], t1)
        };
        // Clamped non-negative first, so truncation is floor (and needs no libm call).
        let mut cx = (start[0].max(0.0) as usize).min(self.nx - 1);
        let mut cy = (start[1].max(0.0) as usize).min(self.ny - 1);
        let axis = |p: f64, v: f64, c: usize| -> (i64, f64, f64) {
            if v > 0.0 {
                (1, (c as f64 + 1.0 - p) / v, 1.0 / v)
            } else if v < 0.0 {
                (-1, (c as f64 - p) / v, -1.0 / v)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (sx, mut next_x, dtx) = axis(gx, d.x / cell, cx);
        let (sy, mut next_y, dty) = axis(gy, d.y / cell, cy);
        let mut best: Option<usize> = None;
        let mut best_t = limit;
        let found = |best: Option<usize>, t: f64| best.map(|i| (i, t));
        loop {
            let c = cy * self.nx + cx;
            for k in self.starts[c] as usize..self.starts[c + 1] as usize {
                if let Some(t) = self.edges[k].cross(o, d) {
                    if t < best_t {
                        best_t = t;
                        best = Some(k);
                    }
                }
            }
            let leave = next_x.min(next_y);
            // A wall exactly at the boundary may also be listed in the next cell only.
            if best_t < leave || leave > t1 {
                return found(best, best_t);
            }
            if next_x < next_y {
                let n = cx as i64 + sx;
                if n < 0 || n >= self.nx as i64 {
                    return found(best, best_t);
                }
                cx = n as usize;
                next_x += dtx;
            } else {
                let n = cy as i64 + sy;
                if n < 0 || n >= self.ny as i64 {
                    return found(best, best_t);
                }
                cy = n as usize;
                next_y += dty;
            }
        }
    }

    /// Grid cells within `r_m` of `p` (floor plane): (columns, rows).
    fn cells_around(
        &self,
        p: [f64; 2],
        r_m: f64,
    ) -> (
        core::ops::RangeInclusive<usize>,
        core::ops::RangeInclusive<usize>,
    ) {
        let cell = self.cell_m;
        let span = |v: f64, o: f64, n: usize| {
            // Truncation is floor here: the argument is clamped non-negative first.
            let lo = (((v - r_m - o) / cell).max(0.0) as usize).min(n - 1);
            let hi = (((v + r_m - o) / cell).max(0.0) as usize).min(n - 1);
            lo..=hi
        };
        (
            span(p[0], self.origin[0], self.nx),
            span(p[1], self.origin[1], self.ny),
        )
    }

    /// Distance from `p` (floor plane) to the nearest wall, capped at `cap_m`: only the grid
    /// cells within the cap are searched, so the cost does not grow with the world.
    pub fn clearance(&self, p: [f64; 2], cap_m: f64) -> f64 {
        let (xs, ys) = self.cells_around(p, cap_m);
        let mut best = cap_m;
        for cy in ys {
            for cx in xs.clone() {
                let c = cy * self.nx + cx;
                for &i in &self.items[self.starts[c] as usize..self.starts[c + 1] as usize] {
                    best = best.min(self.walls[i as usize].distance(p));
                }
            }
        }
        best
    }

    /// Indices of the walls within `r_m` of `p` (floor plane), ascending, each once.
    pub(crate) fn walls_near(&self, p: [f64; 2], r_m: f64, out: &mut Vec<u32>) {
        out.clear();
        let (xs, ys) = self.cells_around(p, r_m);
        for cy in ys {
            for cx in xs.clone() {
                let c = cy * self.nx + cx;
                out.extend_from_slice(
                    &self.items[self.starts[c] as usize..self.starts[c + 1] as usize],
                );
            }
        }
        out.sort_unstable();
        out.dedup();
        out.retain(|&i| self.walls[i as usize].distance(p) <= r_m);
    }

    /// The walls this scene was built from.
    pub fn walls(&self) -> &[Segment] {
        &self.walls
    }
}

/// A wall as the ray tests take it: one end and the vector to the other, worked out once
/// rather than for every ray that tests it (the same values, so the same results).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Edge {
    a: [f64; 2],
    e: [f64; 2],
}

impl Edge {
    pub(crate) fn of(s: &Segment) -> Self {
        Self {
            a: s.a,
            e: [s.b[0] - s.a[0], s.b[1] - s.a[1]],
        }
    }

    /// What a ray along `d` meets when it hits this wall at distance `t`.
    #[inline(always)]
    fn hit(&self, d: Vec3, t: f64) -> Hit {
        let [ex, ey] = self.e;
        Hit {
            range_m: t,
            cos_incidence: (d.x * ey - d.y * ex).abs() / (ex * ex + ey * ey).sqrt(),
        }
    }

    /// Ray (3-D, walls are vertical) against this wall: distance along the ray.
    #[inline(always)]
    fn cross(&self, o: Vec3, d: Vec3) -> Option<f64> {
        let [ex, ey] = self.e;
        let denom = d.x * ey - d.y * ex;
        let (ax, ay) = (self.a[0] - o.x, self.a[1] - o.y);
        // t = t_num / denom must be >= 0 and u = u_num / denom in [0, 1]: compared by sign so
        // that the one division happens only for actual hits (this is the inner loop of every
        // beam). All three are multiplied by the sign of denom (exact) and the tests are
        // combined without short-circuit: which side a wall faces is a coin toss per beam, and
        // branching on it was mispredicted about half the time.
        let t_num = ax * ey - ay * ex;
        let u_num = ax * d.y - ay * d.x;
        let sign = 1.0f64.copysign(denom);
        let (t, u, den) = (t_num * sign, u_num * sign, denom * sign);
        let hit = (den > 0.0) & (t >= 0.0) & (u >= 0.0) & (u <= den);
        hit.then(|| t_num / denom)
    }
}

/// What a ray along `d` meets when it hits wall `s` at distance `t`.
pub(crate) fn wall_hit(s: &Segment, d: Vec3, t: f64) -> Hit {
    Edge::of(s).hit(d, t)
}

/// Ray (3-D, walls are vertical) against a wall segment: distance along the ray.
#[inline(always)]
pub(crate) fn hit_segment(o: Vec3, d: Vec3, s: &Segment) -> Option<f64> {
    Edge::of(s).cross(o, d)
}

/// Ray against a vertical cylinder standing on the floor.
fn hit_cylinder(o: Vec3, d: Vec3, c: &Cylinder) -> Option<f64> {
    let (px, py) = (o.x - c.center[0], o.y - c.center[1]);
    let a = d.x * d.x + d.y * d.y;
    if a == 0.0 {
        return None;
    }
    let b = px * d.x + py * d.y;
    let cc = px * px + py * py - c.radius_m * c.radius_m;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    let z = o.z + t * d.z;
    (t >= 0.0 && (0.0..=c.height_m).contains(&z)).then_some(t)
}

/// Conservative segment-versus-square test used when bucketing walls into cells.
fn segment_touches_box(s: &Segment, lo: [f64; 2], size: f64) -> bool {
    let eps = 1e-9;
    let (x0, y0, x1, y1) = (
        lo[0] - eps,
        lo[1] - eps,
        lo[0] + size + eps,
        lo[1] + size + eps,
    );
    // Liang-Barsky clipping of the segment to the box.
    let (dx, dy) = (s.b[0] - s.a[0], s.b[1] - s.a[1]);
    let (mut u0, mut u1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, s.a[0] - x0),
        (dx, x1 - s.a[0]),
        (-dy, s.a[1] - y0),
        (dy, y1 - s.a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                u0 = u0.max(r);
            } else {
                u1 = u1.min(r);
            }
        }
    }
    u0 <= u1
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn room() -> (World, Scene) {
        let w = World::parse("start 1 1 0\nceiling 2.5\noutline 0 0 6 0 6 4 0 4\n").unwrap();
        let s = Scene::new(&w);
        (w, s)
    }

    /// Brute force: every wall, floor and ceiling, no grid.
    fn reference(w: &World, o: Vec3, d: Vec3, max: f64) -> Option<f64> {
        let mut best = max;
        for s in &w.walls {
            if let Some(t) = hit_segment(o, d, s) {
                best = best.min(t);
            }
        }
        if d.z < 0.0 {
            best = best.min(-o.z / d.z);
        } else if d.z > 0.0 {
            best = best.min((w.ceiling_m - o.z) / d.z);
        }
        (best < max).then_some(best)
    }

    #[test]
    fn level_rays_hit_the_walls_at_known_ranges() {
        let (_, s) = room();
        let o = Vec3::new(1.0, 1.0, 1.0);
        let r = |d: Vec3| s.cast(o, d, 30.0, &[]).unwrap().range_m;
        assert!((r(Vec3::new(1.0, 0.0, 0.0)) - 5.0).abs() < 1e-12);
        assert!((r(Vec3::new(-1.0, 0.0, 0.0)) - 1.0).abs() < 1e-12);
        assert!((r(Vec3::new(0.0, 1.0, 0.0)) - 3.0).abs() < 1e-12);
        let diag = Vec3::new(1.0, 1.0, 0.0) * core::f64::consts::FRAC_1_SQRT_2;
        assert!((r(diag) - 3.0 * core::f64::consts::SQRT_2).abs() < 1e-12);
        assert!(
            s.cast(o, Vec3::new(1.0, 0.0, 0.0), 4.0, &[]).is_none(),
            "beyond max range"
        );
    }

    #[test]
    fn rolled_scan_plane_sees_a_longer_wall_or_the_floor() {
        let (_, s) = room();
        let o = Vec3::new(1.0, 1.0, 1.0);
        // Rolled by 10 degrees, the beam along body y tilts down: it meets the +y wall 3 m away
        // at 3 / cos(10°), lower on the wall.
        let roll = 10f64.to_radians();
        let d = Vec3::new(0.0, roll.cos(), -roll.sin());
        let h = s.cast(o, d, 30.0, &[]).unwrap();
        assert!((h.range_m - 3.0 / roll.cos()).abs() < 1e-12);
        // Rolled by 30 degrees, the same beam hits the floor at 1 / sin(30°) = 2 m.
        let roll = 30f64.to_radians();
        let d = Vec3::new(0.0, roll.cos(), -roll.sin());
        let h = s.cast(o, d, 30.0, &[]).unwrap();
        assert!((h.range_m - 2.0).abs() < 1e-12 && (h.cos_incidence - 0.5).abs() < 1e-12);
    }

    #[test]
    fn people_block_beams_below_their_height() {
        let (_, s) = room();
        let person = [Cylinder {
            center: [3.0, 1.0],
            radius_m: 0.25,
            height_m: 1.75,
        }];
        let hit = s
            .cast(
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, 0.0, 0.0),
                30.0,
                &person,
            )
            .unwrap();
        assert!((hit.range_m - 1.75).abs() < 1e-12);
        let over = s
            .cast(
                Vec3::new(1.0, 1.0, 2.0),
                Vec3::new(1.0, 0.0, 0.0),
                30.0,
                &person,
            )
            .unwrap();
        assert!(
            (over.range_m - 5.0).abs() < 1e-12,
            "a beam above the head reaches the wall"
        );
    }

    #[test]
    fn clearance_is_the_distance_to_the_nearest_wall_capped() {
        let (w, s) = room();
        for p in [[1.0, 1.0], [3.0, 2.0], [5.9, 0.2], [0.3, 3.5]] {
            let exact = w.clearance(p);
            assert!((s.clearance(p, 10.0) - exact).abs() < 1e-12, "{p:?}");
            assert!(
                (s.clearance(p, 0.5) - exact.min(0.5)).abs() < 1e-12,
                "{p:?}"
            );
        }
    }

    /// A ray from `o` at `yaw` and `tilt` (rad) finds the wall a test of every wall finds, at
    /// the same range.
    fn agrees_with_brute_force(
        w: &World,
        s: &Scene,
        o: Vec3,
        yaw: f64,
        tilt: f64,
        max: f64,
    ) -> Result<(), TestCaseError> {
        let d = Vec3::new(tilt.cos() * yaw.cos(), tilt.cos() * yaw.sin(), tilt.sin());
        let got = s.cast(o, d, max, &[]).map(|h| h.range_m);
        let want = reference(w, o, d, max);
        match (got, want) {
            (Some(a), Some(b)) => prop_assert!((a - b).abs() < 1e-9, "{a} vs {b}"),
            (None, None) => {}
            other => prop_assert!(false, "{other:?}"),
        }
        Ok(())
    }

    proptest! {
        #[test]
        fn grid_traversal_agrees_with_brute_force(
            ox in 0.05f64..5.95, oy in 0.05f64..3.95, oz in 0.1f64..2.4,
            yaw in -3.2f64..3.2, tilt in -0.6f64..0.6, max in 0.5f64..12.0,
            bx in 0.5f64..5.0, by in 0.5f64..3.5,
        ) {
            let text = format!("start 1 1 0\nceiling 2.5\noutline 0 0 6 0 6 4 0 4\nwall {bx} {by} {} {}\nwall 2 0.5 2.7 3.1\n", bx + 0.7, by + 0.3);
            let w = World::parse(&text).unwrap();
            agrees_with_brute_force(&w, &Scene::new(&w), Vec3::new(ox, oy, oz), yaw, tilt, max)?;
        }

        /// Rays from outside the grid are clipped to it first; those from inside skip that.
        #[test]
        fn rays_from_outside_agree_with_brute_force(
            ox in -10.0f64..16.0, oy in -10.0f64..14.0, oz in 0.1f64..2.4,
            yaw in -3.2f64..3.2, tilt in -0.3f64..0.3, max in 0.5f64..30.0,
        ) {
            let (w, s) = room();
            agrees_with_brute_force(&w, &s, Vec3::new(ox, oy, oz), yaw, tilt, max)?;
        }

        /// The coverage's level rays: the same range as a full cast, to the bit.
        #[test]
        fn wall_range_is_the_range_of_a_level_cast(
            ox in 0.5f64..19.5, oy in 0.5f64..9.5, yaw in -3.2f64..3.2, max in 0.5f64..30.0,
        ) {
            let s = Scene::new(&World::shipped("office").unwrap().unwrap());
            let o = Vec3::new(ox, oy, 1.0);
            let d = Vec3::new(yaw.cos(), yaw.sin(), 0.0);
            prop_assert_eq!(s.wall_range(o, d, max), s.cast(o, d, max, &[]).map(|h| h.range_m));
        }

        #[test]
        fn hits_lie_on_a_surface_inside_the_room(
            ox in 0.05f64..5.95, oy in 0.05f64..3.95, oz in 0.1f64..2.4,
            yaw in -3.2f64..3.2, tilt in -1.5f64..1.5,
        ) {
            let (_, s) = room();
            let o = Vec3::new(ox, oy, oz);
            let d = Vec3::new(tilt.cos() * yaw.cos(), tilt.cos() * yaw.sin(), tilt.sin());
            let h = s.cast(o, d, 100.0, &[]).unwrap();
            let p = o + d * h.range_m;
            let on_surface = [p.x, 6.0 - p.x, p.y, 4.0 - p.y, p.z, 2.5 - p.z].iter().any(|v| v.abs() < 1e-9);
            prop_assert!(on_surface, "{p:?}");
            prop_assert!(h.cos_incidence > 0.0 && h.cos_incidence <= 1.0 + 1e-12);
        }
    }
}
