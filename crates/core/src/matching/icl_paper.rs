//! Seed 000 Fig. 4, as written: translation-only gradient descent on the point-to-line cost,
//! a fixed number of iterations, and for every point the two closest points of the previous
//! revolution found by brute force (O(N²) per iteration, as in the paper).
//!
//! Two readings of the pseudocode are fixed here: eq. 4's y_CL uses the corrected formula (see
//! the seeds' README), and the accumulated displacement is the shift actually applied to the
//! points (-alpha * delta summed), because line 12's `Delta += delta` would not be in metres.

use super::prepared::PreparedScan;
use crate::geom::{Pose2, Vec2};

/// Closest point to `p3` on the line through `p1` and `p2` (seed 000 eq. 4, typo fixed).
pub fn closest_point_on_line(p1: Vec2, p2: Vec2, p3: Vec2) -> Option<Vec2> {
    let a = p2.y - p1.y;
    let b = p1.x - p2.x;
    let c = -b * p1.y - a * p1.x;
    let d = a * a + b * b;
    if d <= 0.0 {
        return None;
    }
    Some(Vec2::new(
        (b * (b * p3.x - a * p3.y) - a * c) / d,
        (a * (-b * p3.x + a * p3.y) - b * c) / d,
    ))
}

/// The two reference points closest to `q`, by exhaustive search.
fn two_closest<const N: usize>(reference: &PreparedScan<N>, q: Vec2) -> Option<(Vec2, Vec2)> {
    let mut best = [(f32::INFINITY, Vec2::ZERO); 2];
    for &m in reference.points() {
        let d = (m - q).norm_squared();
        if d < best[0].0 {
            best[1] = best[0];
            best[0] = (d, m);
        } else if d < best[1].0 {
            best[1] = (d, m);
        }
    }
    best[1].0.is_finite().then_some((best[0].1, best[1].1))
}

/// Runs Fig. 4 from `guess` (its rotation is kept fixed: the paper estimates translation only).
pub fn run<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    guess: Pose2,
    rate_per_point: f32,
    iterations: u16,
) -> Pose2 {
    let alpha = rate_per_point / current.len().max(1) as f32;
    let mut t = guess.translation();
    let rot = Pose2::new(0.0, 0.0, guess.theta);
    for _ in 0..iterations {
        let mut delta = Vec2::ZERO;
        for &p in current.points() {
            let q = rot.rotate(p) + t;
            let Some((p1, p2)) = two_closest(reference, q) else {
                continue;
            };
            if let Some(cl) = closest_point_on_line(p1, p2, q) {
                delta = delta + (q - cl);
            }
        }
        t = t - delta * alpha;
    }
    Pose2::new(t.x, t.y, guess.theta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_on_a_diagonal_line() {
        // Line y = x; the foot of (2, 0) is (1, 1).
        let cl = closest_point_on_line(
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 3.0),
            Vec2::new(2.0, 0.0),
        )
        .unwrap();
        assert!(
            (cl.x - 1.0).abs() < 1e-6 && (cl.y - 1.0).abs() < 1e-6,
            "{cl:?}"
        );
    }

    #[test]
    fn coincident_points_define_no_line() {
        assert!(
            closest_point_on_line(Vec2::new(1.0, 1.0), Vec2::new(1.0, 1.0), Vec2::ZERO).is_none()
        );
    }
}
