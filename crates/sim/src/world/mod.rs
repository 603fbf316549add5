//! The world and its geometry: what the vehicle flies in and what its sensors see.
//!
//! - this module: indoor worlds, wall segments extruded from the floor (z = 0) to the ceiling,
//!   a take-off point, a survey path and walking people, parsed from the small line format
//!   documented in `crates/sim/WORLDS.md` (the shipped worlds live in `crates/sim/worlds/`);
//! - [`occupancy`]: occupancy grids (a map image) and worlds traced from them;
//! - [`scene`]: the world as ray-casting geometry for the lidar and the sonar;
//! - [`nearby`]: the walls near a point, gathered once for many rays;
//! - [`clearance`]: the distance from the vehicle to the nearest wall, for crash checks.

pub mod check;
pub mod clearance;
pub mod nearby;
pub mod occupancy;
pub mod scene;

use crate::math::Vec3;
use check::{check_enclosed, unknown_keyword, world_number, OnceOnly, KEYWORDS};

/// A wall from `a` to `b` (world x, y in metres), floor to ceiling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub a: [f64; 2],
    pub b: [f64; 2],
}

impl Segment {
    pub fn new(a: [f64; 2], b: [f64; 2]) -> Self {
        Self { a, b }
    }

    /// Distance from a point to the segment, m.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        let (ex, ey) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let (px, py) = (p[0] - self.a[0], p[1] - self.a[1]);
        let len2 = ex * ex + ey * ey;
        let u = if len2 > 0.0 {
            ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (dx, dy) = (px - u * ex, py - u * ey);
        (dx * dx + dy * dy).sqrt()
    }
}

/// A person walking back and forth between two points (seed 000 Fig. 6: people in the scan).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walker {
    pub from: [f64; 2],
    pub to: [f64; 2],
    pub speed_mps: f64,
}

impl Walker {
    /// Body radius and height of a walking person, m.
    pub const RADIUS_M: f64 = 0.25;
    pub const HEIGHT_M: f64 = 1.75;

    /// Where the person stands at time `t_s` (a triangle wave between the two points).
    pub fn position(&self, t_s: f64) -> [f64; 2] {
        let len = (self.to[0] - self.from[0]).hypot(self.to[1] - self.from[1]);
        if len == 0.0 || self.speed_mps <= 0.0 {
            return self.from;
        }
        let s = (self.speed_mps * t_s).rem_euclid(2.0 * len);
        let u = if s <= len { s / len } else { 2.0 - s / len };
        [
            self.from[0] + u * (self.to[0] - self.from[0]),
            self.from[1] + u * (self.to[1] - self.from[1]),
        ]
    }
}

/// A parsed world.
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    pub name: String,
    /// Ceiling height; walls span 0..ceiling, m.
    pub ceiling_m: f64,
    /// Take-off point on the floor (x, y) and heading, m and rad.
    pub start: [f64; 3],
    pub walls: Vec<Segment>,
    /// Solid polygons (pillars, cabinets): their outlines are also in `walls`.
    pub blocks: Vec<Vec<[f64; 2]>>,
    /// Survey waypoints (x, y), flown at `altitude_m`.
    pub path: Vec<[f64; 2]>,
    pub altitude_m: f64,
    pub walkers: Vec<Walker>,
}

/// A world file error: the 1-based line and what was wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldError {
    pub line: usize,
    pub reason: String,
}

impl core::fmt::Display for WorldError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.reason)
        } else {
            write!(f, "line {}: {}", self.line, self.reason)
        }
    }
}

impl std::error::Error for WorldError {}

/// The shipped worlds, by name.
pub const SHIPPED: &[(&str, &str)] = &[
    ("room", include_str!("../../worlds/room.world")),
    ("office", include_str!("../../worlds/office.world")),
    ("building", include_str!("../../worlds/building.world")),
    ("intel", include_str!("../../worlds/intel.world")),
    ("hall", include_str!("../../worlds/hall.world")),
];

fn closed_loop(points: &[[f64; 2]]) -> impl Iterator<Item = Segment> + '_ {
    (0..points.len()).map(move |i| Segment::new(points[i], points[(i + 1) % points.len()]))
}

fn points(nums: &[f64]) -> Vec<[f64; 2]> {
    nums.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

impl World {
    /// A shipped world by name.
    pub fn shipped(name: &str) -> Option<Result<World, WorldError>> {
        SHIPPED
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, text)| World::parse(text))
    }

    /// Parses the line format of `WORLDS.md`.
    pub fn parse(text: &str) -> Result<World, WorldError> {
        let mut w = World {
            name: String::new(),
            ceiling_m: 2.5,
            start: [0.0; 3],
            walls: Vec::new(),
            blocks: Vec::new(),
            path: Vec::new(),
            altitude_m: 1.0,
            walkers: Vec::new(),
        };
        let mut start_line = None;
        let mut path_lines = Vec::new();
        let mut once = OnceOnly::default();
        // Editors on some systems put a byte-order mark in front of UTF-8 text; it is not a word.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let err = |reason: String| WorldError { line, reason };
            let content = raw.split('#').next().unwrap_or("").trim();
            let mut words = content.split_whitespace();
            let Some(key) = words.next() else { continue };
            once.note(key, line).map_err(err)?;
            if key == "name" {
                w.name = words.collect::<Vec<_>>().join(" ");
                continue;
            }
            if !KEYWORDS.contains(&key) {
                return Err(err(unknown_keyword(key)));
            }
            let nums = words
                .map(|s| world_number(s).map_err(err))
                .collect::<Result<Vec<f64>, _>>()?;
            let want = |n: usize| {
                if nums.len() == n {
                    Ok(())
                } else {
                    Err(err(format!(
                        "`{key}` takes {n} numbers, got {}",
                        nums.len()
                    )))
                }
            };
            let want_points = |min: usize| {
                if nums.len() >= 2 * min && nums.len() % 2 == 0 {
                    Ok(())
                } else {
                    Err(err(format!(
                        "`{key}` takes at least {min} x y pairs, got {} numbers",
                        nums.len()
                    )))
                }
            };
            match key {
                "ceiling" => {
                    want(1)?;
                    if nums[0] <= 0.0 {
                        return Err(err("ceiling must be above the floor".into()));
                    }
                    w.ceiling_m = nums[0];
                }
                "altitude" => {
                    want(1)?;
                    w.altitude_m = nums[0];
                }
                "start" => {
                    want(3)?;
                    w.start = [nums[0], nums[1], nums[2]];
                    start_line = Some(line);
                }
                "wall" => {
                    want(4)?;
                    if nums[0] == nums[2] && nums[1] == nums[3] {
                        return Err(err("wall has zero length".into()));
                    }
                    w.walls
                        .push(Segment::new([nums[0], nums[1]], [nums[2], nums[3]]));
                }
                "outline" | "block" => {
                    want_points(3)?;
                    let pts = points(&nums);
                    w.walls.extend(closed_loop(&pts));
                    if key == "block" {
                        w.blocks.push(pts);
                    }
                }
                "box" => {
                    want(4)?;
                    let [x0, y0, x1, y1] = [nums[0], nums[1], nums[2], nums[3]];
                    if x1 <= x0 || y1 <= y0 {
                        return Err(err("box needs xmin ymin xmax ymax with max > min".into()));
                    }
                    let pts = vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
                    w.walls.extend(closed_loop(&pts));
                    w.blocks.push(pts);
                }
                "path" => {
                    want_points(1)?;
                    w.path.extend(points(&nums));
                    path_lines.resize(w.path.len(), line);
                }
                "person" => {
                    want(5)?;
                    if nums[4] < 0.0 {
                        return Err(err("person speed must not be negative".into()));
                    }
                    w.walkers.push(Walker {
                        from: [nums[0], nums[1]],
                        to: [nums[2], nums[3]],
                        speed_mps: nums[4],
                    });
                }
                other => return Err(err(unknown_keyword(other))),
            }
        }
        let whole = |reason: &str| WorldError {
            line: 0,
            reason: reason.into(),
        };
        if w.walls.is_empty() {
            return Err(whole("world has no walls"));
        }
        let Some(start_line) = start_line else {
            return Err(whole("world has no `start` line"));
        };
        check_enclosed(&w, start_line, &path_lines)?;
        if w.altitude_m <= 0.0 || w.altitude_m >= w.ceiling_m {
            return Err(whole("altitude must lie between floor and ceiling"));
        }
        Ok(w)
    }

    /// The world in the line format of `WORLDS.md` (walls as `wall` lines; blocks become plain
    /// walls, people and paths are kept), parseable by [`World::parse`].
    pub fn to_text(&self) -> String {
        // Millimetres are plenty for walls; trailing zeros are trimmed to keep files small.
        let n = |v: f64| {
            let s = format!("{v:.3}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            if s == "-0" {
                "0".to_string()
            } else {
                s.to_string()
            }
        };
        let mut out = format!(
            "name {}\nceiling {}\nstart {} {} {}\naltitude {}\n",
            self.name,
            n(self.ceiling_m),
            n(self.start[0]),
            n(self.start[1]),
            n(self.start[2]),
            n(self.altitude_m)
        );
        for w in &self.walls {
            out += &format!(
                "wall {} {} {} {}\n",
                n(w.a[0]),
                n(w.a[1]),
                n(w.b[0]),
                n(w.b[1])
            );
        }
        for p in &self.path {
            out += &format!("path {} {}\n", n(p[0]), n(p[1]));
        }
        for p in &self.walkers {
            out += &format!(
                "person {} {} {} {} {}\n",
                n(p.from[0]),
                n(p.from[1]),
                n(p.to[0]),
                n(p.to[1]),
                n(p.speed_mps)
            );
        }
        out
    }

    /// The free point with the most room around it, on a 0.5 m lattice (a take-off point for
    /// worlds that do not name one, such as images).
    pub fn most_open_point(&self) -> [f64; 2] {
        let [x0, y0, x1, y1] = self.bounds();
        let mut best = ([x0, y0], -1.0);
        let (nx, ny) = (((x1 - x0) / 0.5) as usize, ((y1 - y0) / 0.5) as usize);
        for j in 0..=ny {
            for i in 0..=nx {
                let p = [x0 + i as f64 * 0.5, y0 + j as f64 * 0.5];
                let c = self.clearance(p);
                if c > best.1 && !self.inside_block(p) {
                    best = (p, c);
                }
            }
        }
        best.0
    }

    /// Distance from a point to the nearest wall, m.
    pub fn clearance(&self, p: [f64; 2]) -> f64 {
        self.walls
            .iter()
            .map(|s| s.distance(p))
            .fold(f64::INFINITY, f64::min)
    }

    /// True when the point lies inside a solid block.
    pub fn inside_block(&self, p: [f64; 2]) -> bool {
        self.blocks.iter().any(|poly| {
            let mut inside = false;
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                if (a[1] > p[1]) != (b[1] > p[1])
                    && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
                {
                    inside = !inside;
                }
            }
            inside
        })
    }

    /// Checks that a vehicle of `radius_m` fits at `p`: not inside a block, clear of every wall.
    pub fn check_free(&self, p: [f64; 2], radius_m: f64, what: &str) -> Result<(), WorldError> {
        let fail = |reason: String| Err(WorldError { line: 0, reason });
        if self.inside_block(p) {
            return fail(format!(
                "{what} ({:.2}, {:.2}) is inside a solid block",
                p[0], p[1]
            ));
        }
        let c = self.clearance(p);
        if c < radius_m {
            return fail(format!("{what} ({:.2}, {:.2}) is {c:.2} m from a wall, closer than the vehicle radius {radius_m:.2} m", p[0], p[1]));
        }
        Ok(())
    }

    /// Take-off position (on the floor) as a 3-D point.
    pub fn start_position(&self) -> Vec3 {
        Vec3::new(self.start[0], self.start[1], 0.0)
    }

    /// Axis-aligned bounds of the walls: (min x, min y, max x, max y).
    pub fn bounds(&self) -> [f64; 4] {
        self.walls.iter().flat_map(|s| [s.a, s.b]).fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ]
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_worlds_parse_and_their_paths_are_free() {
        for (name, _) in SHIPPED {
            let w = World::shipped(name)
                .unwrap()
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!w.walls.is_empty() && w.path.len() >= 2, "{name}");
            w.check_free([w.start[0], w.start[1]], 0.35, "start")
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            for p in &w.path {
                w.check_free(*p, 0.35, "waypoint")
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
            }
        }
    }

    #[test]
    fn errors_name_the_line_and_reason() {
        let e = World::parse("name x\nstart 0 0 0\nwall 0 0 1\n").unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.reason.contains("4 numbers"), "{e}");
        let e = World::parse("start 0 0 0\nwall 0 0 1 nan\n").unwrap_err();
        assert!(
            e.to_string().starts_with("line 2:") && e.reason.contains("nan"),
            "{e}"
        );
        let e = World::parse("start 0 0 0\nnmae my room\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(
            e.reason
                .contains("unknown keyword `nmae`; did you mean `name`?"),
            "{e}"
        );
        assert!(World::parse("\u{feff}start 1 1 0\noutline 0 0 4 0 4 4 0 4\n").is_ok());
        let e = World::parse("start 0 0 0\nwindow 1 2\n").unwrap_err();
        assert!(e.reason.contains("unknown keyword `window`"), "{e}");
        assert!(World::parse("start 0 0 0\n")
            .unwrap_err()
            .reason
            .contains("no walls"));
    }

    #[test]
    fn start_inside_a_block_or_against_a_wall_is_rejected() {
        let w = World::parse("start 1 1 0\noutline 0 0 4 0 4 4 0 4\nbox 2 2 3 3\n").unwrap();
        assert!(w
            .check_free([2.5, 2.5], 0.3, "start")
            .unwrap_err()
            .reason
            .contains("inside"));
        assert!(w
            .check_free([0.1, 1.0], 0.3, "start")
            .unwrap_err()
            .reason
            .contains("from a wall"));
        assert!(w.check_free([1.0, 1.0], 0.3, "start").is_ok());
    }

    #[test]
    fn text_round_trip() {
        let w = World::shipped("office").unwrap().unwrap();
        let back = World::parse(&w.to_text()).unwrap();
        assert_eq!(
            (back.walls, back.path, back.walkers, back.start),
            (w.walls, w.path, w.walkers, w.start)
        );
    }

    #[test]
    fn walkers_go_back_and_forth() {
        let p = Walker {
            from: [0.0, 0.0],
            to: [2.0, 0.0],
            speed_mps: 1.0,
        };
        assert_eq!(p.position(1.0), [1.0, 0.0]);
        assert_eq!(p.position(2.0), [2.0, 0.0]);
        assert_eq!(p.position(3.0), [1.0, 0.0]);
        assert_eq!(p.position(4.0), [0.0, 0.0]);
    }
}
