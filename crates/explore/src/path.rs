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
    /// given. Corners are dropped while the straight line that replaces them stays on safe
    /// cells, so the length is that of the shortest path to within a cell rather than the
    /// grid's eight-direction detour. A leg from a start or end point that is not on a safe
    /// cell is kept as it is: it is the way out to safe space.
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
        let clear = |a: Vec2, b: Vec2| g.segment_clear(a, b, |k| g.is_safe(k));
        let mut out: Vec<Vec2> = points[..=first].to_vec();
        let mut i = first;
        while i < last {
            let mut j = i + 1;
            while j < last && clear(points[i], points[j + 1]) {
                j += 1;
            }
            out.push(points[j]);
            i = j;
        }
        out.extend_from_slice(&points[last + 1..]);
        out.dedup();
        Self::new(out)
    }

    /// The point `distance_m` along the path beyond the point of the path nearest to `from`
    /// (the goal if the path is shorter); `from` itself for an empty path.
    pub fn lookahead(&self, from: Vec2, distance_m: f32) -> Vec2 {
        let Some(&first) = self.waypoints.first() else {
            return from;
        };
        // The nearest point: segment index and the distance along the path to it.
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
        if self.waypoints.len() == 1 {
            return first;
        }
        self.point_at(best.1 + distance_m)
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
