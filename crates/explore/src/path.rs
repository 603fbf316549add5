//! A planned path as a polyline in the map frame: built from a search's cells with the
//! zig-zag of the grid pulled straight, measured, and followed by a lookahead point.

use crate::plan_grid::PlanGrid;
use plumbline_core::geom::Vec2;

/// A path in the map frame, m.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// Corners of the polyline, from where the vehicle is to the goal.
    pub waypoints: Vec<Vec2>,
    /// Length along the polyline, m.
    pub length_m: f32,
}

impl Path {
    pub fn new(waypoints: Vec<Vec2>) -> Self {
        let length_m = waypoints.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        Self {
            waypoints,
            length_m,
        }
    }

    /// The path from `start` through the centres of `cells` (a search's result) to `end` if
    /// given, pulled taut over the safe cells: the grid's eight-direction zig-zag straightened
    /// and its corners rounded the way a string round a post is, so the length is that of
    /// the shortest path to within a cell. Its legs pass [`PlanGrid::leg_clear`]: they stay
    /// on safe cells, so the path comes no closer to a mapped obstacle than `r_min` less half
    /// a cell's diagonal, and roomy stretches are not pulled into tight cells. A leg from a
    /// start or end point that is not on a safe cell is kept as it is: it is the way out to
    /// safe space.
    pub fn through(g: &PlanGrid, start: Vec2, cells: &[usize], end: Option<Vec2>) -> Self {
        let safe_at = |p: Vec2| g.index_of(p).is_some_and(|k| g.is_safe(k));
        let mut points = Vec::with_capacity(cells.len() + 2);
        let start_safe = safe_at(start);
        points.push(start);
        points.extend(cells.iter().map(|&k| g.center(k)));
        let end_safe = end.is_some_and(safe_at);
        if let Some(e) = end {
            points.push(e);
        }
        // The first and last legs stay fixed unless their outer point is safe.
        let first = usize::from(!start_safe);
        let last = points.len() - 1 - usize::from(end.is_some() && !end_safe);
        let clear = |a: Vec2, b: Vec2| g.leg_clear(a, b);
        let mut inner = shortcut(&points[first..=last], clear);
        tighten(&mut inner, g.cell_m(), clear);
        let inner = shortcut(&inner, clear);
        let mut out: Vec<Vec2> = points[..first].to_vec();
        out.extend_from_slice(&inner);
        out.extend_from_slice(&points[last + 1..]);
        out.dedup();
        Self::new(out)
    }

    /// The point `distance_m` along the path beyond the point of the path nearest to `from`
    /// (the goal if the path is shorter); `from` itself for an empty path.
    pub fn lookahead(&self, from: Vec2, distance_m: f32) -> Vec2 {
        self.lookahead_in_sight(from, distance_m, distance_m, |_, _| true)
    }

    /// Like [`Self::lookahead`], but the point is brought back toward the vehicle in steps of
    /// `step_m` until `in_sight(from, point)` holds (at least one step ahead): round a corner
    /// the point a full lookahead ahead lies across the corner, and a vehicle drawn straight at
    /// it would cut the corner the path goes round.
    pub fn lookahead_in_sight(
        &self,
        from: Vec2,
        distance_m: f32,
        step_m: f32,
        in_sight: impl Fn(Vec2, Vec2) -> bool,
    ) -> Vec2 {
        let Some(&first) = self.waypoints.first() else {
            return from;
        };
        if self.waypoints.len() == 1 {
            return first;
        }
        let nearest = self.nearest_arc_m(from);
        let step_m = if step_m > 0.0 { step_m } else { distance_m };
        let mut ahead = distance_m;
        while ahead > step_m {
            let q = self.point_at(nearest + ahead);
            if in_sight(from, q) {
                return q;
            }
            ahead -= step_m;
        }
        self.point_at(nearest + ahead.max(0.0))
    }

    /// Arc length from the start to the point of the path nearest to `from`, m.
    fn nearest_arc_m(&self, from: Vec2) -> f32 {
        let mut best = (f32::INFINITY, 0.0f32);
        let mut along = 0.0;
        for w in self.waypoints.windows(2) {
            let d = w[1] - w[0];
            let len = d.norm();
            let t = if len > 0.0 {
                ((from - w[0]).dot(d) / (len * len)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let gap = (w[0] + d * t - from).norm();
            if gap < best.0 {
                best = (gap, along + t * len);
            }
            along += len;
        }
        best.1
    }

    /// The point at arc length `s_m` from the start, clamped to the ends.
    pub fn point_at(&self, s_m: f32) -> Vec2 {
        let mut left = s_m.max(0.0);
        for w in self.waypoints.windows(2) {
            let len = (w[1] - w[0]).norm();
            if left <= len && len > 0.0 {
                return w[0] + (w[1] - w[0]) * (left / len);
            }
            left -= len;
        }
        self.waypoints.last().copied().unwrap_or(Vec2::ZERO)
    }
}

/// The corners of `points` that remain when each kept corner is joined to the farthest later
/// one in sight (round a wall's end the grid's corners come in and out of view, so the search
/// runs from the far end).
fn shortcut(points: &[Vec2], clear: impl Fn(Vec2, Vec2) -> bool) -> Vec<Vec2> {
    let Some(&first) = points.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut i = 0;
    while i + 1 < points.len() {
        let j = (i + 2..points.len())
            .rev()
            .find(|&j| clear(points[i], points[j]))
            .unwrap_or(i + 1);
        out.push(points[j]);
        i = j;
    }
    out
}

/// Rounds the corners of a polyline whose ends stay put: each leg is cut into pieces of about
/// two cells, then every inner point moves toward the middle of its neighbours as far as its
/// two legs stay in sight. Points on a straight leg do not move; at a corner they slide inward
/// until the legs touch the unsafe cells, which is where the shortest path runs.
fn tighten(points: &mut Vec<Vec2>, cell_m: f32, clear: impl Fn(Vec2, Vec2) -> bool) {
    const ROUNDS: usize = 24;
    let piece = 2.0 * cell_m;
    let mut dense = Vec::with_capacity(points.len() * 4);
    for w in points.windows(2) {
        let n = ((w[1] - w[0]).norm() / piece).ceil().max(1.0) as usize;
        dense.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * (k as f32 / n as f32)));
    }
    dense.extend(points.last());
    for _ in 0..ROUNDS {
        let mut moved = false;
        for k in 1..dense.len().saturating_sub(1) {
            let (a, p, b) = (dense[k - 1], dense[k], dense[k + 1]);
            let step = (a + b) * 0.5 - p;
            if step.norm() < 1e-3 * cell_m {
                continue;
            }
            for fraction in [1.0, 0.5, 0.25] {
                let q = p + step * fraction;
                if clear(a, q) && clear(q, b) {
                    dense[k] = q;
                    moved = true;
                    break;
                }
            }
        }
        if !moved {
            break;
        }
    }
    *points = dense;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookahead_walks_along_the_path_from_the_nearest_point() {
        let p = Path::new(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
        ]);
        assert_eq!(p.length_m, 4.0);
        let near = |a: Vec2, b: Vec2| (a - b).norm() < 1e-5;
        assert!(near(
            p.lookahead(Vec2::new(0.5, 0.3), 1.0),
            Vec2::new(1.5, 0.0)
        ));
        assert!(near(
            p.lookahead(Vec2::new(1.5, -0.2), 1.0),
            Vec2::new(2.0, 0.5)
        ));
        assert!(near(
            p.lookahead(Vec2::new(5.0, 5.0), 1.0),
            Vec2::new(2.0, 2.0)
        ));
        assert!(near(p.point_at(-1.0), Vec2::new(0.0, 0.0)));
        let empty = Path::new(Vec::new());
        assert_eq!(
            empty.lookahead(Vec2::new(1.0, 1.0), 1.0),
            Vec2::new(1.0, 1.0)
        );
    }
}
