//! What makes a parsed world flyable, checked before any flight so that a bad world is an error
//! naming its line rather than a vehicle flown into the void until it crashes or its battery
//! dies: known keywords (a typo is named with the keyword it likely meant), coordinates a
//! building can have, one of each once-only statement, and a start (and survey waypoints)
//! enclosed by walls.

use super::{Segment, World, WorldError};

/// Largest coordinate (and any other number) in a world file, m: 10 km from the origin is far
/// beyond any building, and keeps every derived grid and distance well inside `f64` precision.
pub const MAX_COORD_M: f64 = 10_000.0;

/// Every statement of the world format (`WORLDS.md`).
pub const KEYWORDS: &[&str] = &[
    "name", "ceiling", "altitude", "start", "wall", "outline", "block", "box", "path", "person",
];

/// Names the unknown word, the closest keyword when one is a likely typo, and all of them.
pub fn unknown_keyword(word: &str) -> String {
    let closest = KEYWORDS
        .iter()
        .map(|k| (strsim::damerau_levenshtein(word, k), *k))
        .min()
        .filter(|(d, k)| *d <= 2 && *d < k.len());
    let hint = closest.map_or(String::new(), |(_, k)| format!("; did you mean `{k}`?"));
    format!(
        "unknown keyword `{word}`{hint} (a line starts with one of: {})",
        KEYWORDS.join(", ")
    )
}

/// Statements that set one value and may appear once.
const ONCE: &[&str] = &["name", "start", "ceiling", "altitude"];

/// Remembers the line of each once-only statement, to refuse a second one.
#[derive(Default)]
pub struct OnceOnly {
    seen: Vec<(&'static str, usize)>,
}

impl OnceOnly {
    /// An error naming the first line when `key` is a once-only statement seen before.
    pub fn note(&mut self, key: &str, line: usize) -> Result<(), String> {
        let Some(&once) = ONCE.iter().find(|k| **k == key) else {
            return Ok(());
        };
        if let Some((_, first)) = self.seen.iter().find(|(k, _)| *k == once) {
            return Err(format!(
                "a second `{key}` statement (the first is on line {first}): a world has one"
            ));
        }
        self.seen.push((once, line));
        Ok(())
    }
}

/// A number in a world file: finite and within [`MAX_COORD_M`].
pub fn world_number(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_COORD_M => Ok(v),
        Ok(v) if v.is_finite() => Err(format!(
            "`{text}` is more than {MAX_COORD_M} m from the origin: a world is a building"
        )),
        _ => Err(format!("`{text}` is not a finite number")),
    }
}

/// Rays cast from a point to decide whether walls enclose it.
const RAYS: usize = 32;

/// True when every one of [`RAYS`] rays from `p` meets a wall: the point is inside the world
/// (a room, a corridor, through doors), not outside every wall where nothing would ever stop
/// the vehicle or return a lidar beam.
pub fn enclosed(walls: &[Segment], p: [f64; 2]) -> bool {
    (0..RAYS).all(|k| {
        // An odd offset keeps rays off the corners of axis-aligned outlines.
        let a = (k as f64 + 0.37) * std::f64::consts::TAU / RAYS as f64;
        let d = [a.cos(), a.sin()];
        walls.iter().any(|s| ray_hits(p, d, s))
    })
}

/// The start and every survey waypoint enclosed by walls, or an error naming the line that
/// placed the first one that is not.
pub fn check_enclosed(
    w: &World,
    start_line: usize,
    path_lines: &[usize],
) -> Result<(), WorldError> {
    let outside = |what: String, p: [f64; 2], line: usize| WorldError {
        line,
        reason: format!(
            "{what} ({}, {}) is not enclosed by walls: some directions from it meet no wall, so \
             nothing would stop the vehicle or return a lidar beam there",
            p[0], p[1]
        ),
    };
    let start = [w.start[0], w.start[1]];
    if !enclosed(&w.walls, start) {
        return Err(outside("the start".into(), start, start_line));
    }
    match w
        .path
        .iter()
        .enumerate()
        .find(|(_, p)| !enclosed(&w.walls, **p))
    {
        Some((k, p)) => Err(outside(format!("waypoint {}", k + 1), *p, path_lines[k])),
        None => Ok(()),
    }
}

fn ray_hits(p: [f64; 2], d: [f64; 2], s: &Segment) -> bool {
    let e = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
    let denom = d[0] * e[1] - d[1] * e[0];
    if denom.abs() < 1e-12 {
        return false;
    }
    let w = [s.a[0] - p[0], s.a[1] - p[1]];
    let t = (w[0] * e[1] - w[1] * e[0]) / denom;
    let u = (w[0] * d[1] - w[1] * d[0]) / denom;
    t > 0.0 && (0.0..=1.0).contains(&u)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(half: f64) -> Vec<Segment> {
        let c = [[-half, -half], [half, -half], [half, half], [-half, half]];
        (0..4).map(|i| Segment::new(c[i], c[(i + 1) % 4])).collect()
    }

    #[test]
    fn inside_a_room_is_enclosed_outside_it_is_not() {
        let walls = square(2.0);
        assert!(enclosed(&walls, [0.0, 0.0]));
        assert!(enclosed(&walls, [1.9, -1.9]));
        assert!(!enclosed(&walls, [3.0, 0.0]));
        assert!(!enclosed(&walls, [1e6, 1e6]));
        // A room with a doorway: the door lets one direction out, so a start right in front of
        // it on the outside is not enclosed, and inside the room it is only if a wall lies
        // beyond the door.
        let mut open = square(2.0);
        open[1] = Segment::new([2.0, -2.0], [2.0, -0.5]);
        open.push(Segment::new([2.0, 0.5], [2.0, 2.0]));
        assert!(!enclosed(&open, [0.0, 0.0]));
        open.push(Segment::new([6.0, -6.0], [6.0, 6.0]));
        assert!(enclosed(&open, [0.0, 0.0]));
    }

    #[test]
    fn numbers_are_finite_and_bounded() {
        assert_eq!(world_number("-9999.5"), Ok(-9999.5));
        for bad in ["1e30", "-1e7", "inf", "nan", "x"] {
            assert!(world_number(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn once_only_statements_name_the_first_line() {
        let mut once = OnceOnly::default();
        assert!(once.note("start", 2).is_ok());
        assert!(once.note("wall", 3).is_ok() && once.note("wall", 4).is_ok());
        let e = once.note("start", 7).unwrap_err();
        assert!(e.contains("line 2"), "{e}");
    }
}
