//! Seed 000 Fig. 4, as written: translation-only gradient descent on the point-to-line cost,
//! a fixed number of iterations, and for every point the two closest points of the previous
//! revolution found by brute force (O(N²) per iteration, as in the paper).
//!
//! Sec. 4.2's rejection is an option ([`PaperRejection`]): a point whose cost J (eq. 3) is
//! "significantly larger" than the previous revolution's squared displacement
//! (dx_{k-1}^2 + dy_{k-1}^2) is left out of the sums. The paper puts no number on
//! "significantly"; `gain` is it, and `floor_m` (0 as written) is an optional floor on the
//! threshold. J is the point's cost where the iteration has moved it, so a point rejected early
//! may count once the estimate reaches it.
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

/// Seed 000 sec. 4.2's rule: a point is rejected when its cost J exceeds
/// `gain * (dx_{k-1}^2 + dy_{k-1}^2) + floor_m^2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperRejection {
    /// The previous revolution's displacement (dx_{k-1}, dy_{k-1}), m.
    pub previous: Vec2,
    /// How many times the previous squared displacement counts as "significantly larger".
    pub gain: f32,
    /// Floor on the threshold, m (0: the rule as written).
    pub floor_m: f32,
}

impl PaperRejection {
    fn threshold_m2(&self) -> f32 {
        self.gain * self.previous.norm_squared() + self.floor_m * self.floor_m
    }
}

/// What Fig. 4 found: the pose, and how many points sec. 4.2 rejected in its last iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperMatch {
    pub pose: Pose2,
    pub rejected: u16,
}

/// Runs Fig. 4 from `guess` (its rotation is kept fixed: the paper estimates translation only),
/// with sec. 4.2's rejection when `rejection` is given.
pub fn run<const N: usize>(
    reference: &PreparedScan<N>,
    current: &PreparedScan<N>,
    guess: Pose2,
    rate_per_point: f32,
    iterations: u16,
    rejection: Option<PaperRejection>,
) -> PaperMatch {
    let alpha = rate_per_point / current.len().max(1) as f32;
    let max_cost = rejection.map(|r| r.threshold_m2());
    let mut t = guess.translation();
    let rot = Pose2::new(0.0, 0.0, guess.theta);
    let mut rejected = 0;
    for _ in 0..iterations {
        let mut delta = Vec2::ZERO;
        rejected = 0;
        for &p in current.points() {
            let q = rot.rotate(p) + t;
            let Some((p1, p2)) = two_closest(reference, q) else {
                continue;
            };
            if let Some(cl) = closest_point_on_line(p1, p2, q) {
                let residual = q - cl;
                if max_cost.is_some_and(|m| residual.norm_squared() > m) {
                    rejected += 1;
                    continue;
                }
                delta = delta + residual;
            }
        }
        t = t - delta * alpha;
    }
    PaperMatch {
        pose: Pose2::new(t.x, t.y, guess.theta),
        rejected,
    }
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

    /// A 360-beam scan from `lidar` (no rotation) of a 6 m x 4 m room (walls at x = +-3,
    /// y = +-2), with a person (a 0.2 m radius circle) at `person` when given.
    fn scan(lidar: Vec2, person: Option<Vec2>) -> PreparedScan<360> {
        let mut scan = crate::scan::Scan::<360>::new(0.0);
        for k in 0..360 {
            let a = (k as f32).to_radians();
            let d = Vec2::new(libm::cosf(a), libm::sinf(a));
            let mut r = f32::INFINITY;
            for (along, room) in [
                (d.x, 3.0 - lidar.x),
                (-d.x, 3.0 + lidar.x),
                (d.y, 2.0 - lidar.y),
                (-d.y, 2.0 + lidar.y),
            ] {
                if along > 1e-6 {
                    r = r.min(room / along);
                }
            }
            if let Some(c) = person {
                // |lidar + r d - c| = 0.2: the nearer root, if the beam meets the circle.
                let o = lidar - c;
                let (b, cc) = (o.dot(d), o.norm_squared() - 0.04);
                let disc = b * b - cc;
                if disc >= 0.0 && -b - libm::sqrtf(disc) > 0.0 {
                    r = r.min(-b - libm::sqrtf(disc));
                }
            }
            scan.push(crate::scan::Beam::new(a, r)).unwrap();
        }
        let mut prepared = PreparedScan::default();
        prepared.load(&scan).unwrap();
        prepared
    }

    /// Fig. 4 from the identity with the default rate and iteration count.
    fn fig_4(
        reference: &PreparedScan<360>,
        current: &PreparedScan<360>,
        rejection: Option<PaperRejection>,
    ) -> PaperMatch {
        run(reference, current, Pose2::IDENTITY, 1.0, 20, rejection)
    }

    /// Beams of a scan from the origin that end on the person at `c`.
    fn person_hits(c: Vec2) -> u16 {
        let with = scan(Vec2::ZERO, Some(c));
        let without = scan(Vec2::ZERO, None);
        with.points()
            .iter()
            .zip(without.points())
            .filter(|(a, b)| (**a - **b).norm() > 1e-3)
            .count() as u16
    }

    #[test]
    fn rejection_drops_a_walking_person_and_keeps_the_still_room() {
        // A stationary lidar; between revolutions a person walks 0.5 m across its view (clear
        // of where they stood: a point where the person was is no outlier by J).
        let (before, after) = (Vec2::new(1.2, -0.35), Vec2::new(1.2, 0.15));
        let reference = scan(Vec2::ZERO, Some(before));
        let current = scan(Vec2::ZERO, Some(after));
        let rejection = PaperRejection {
            previous: Vec2::new(0.005, 0.0),
            gain: 4.0,
            floor_m: 0.0,
        };
        let with = fig_4(&reference, &current, Some(rejection));
        let without = fig_4(&reference, &current, None);
        let hits = person_hits(after);
        assert!(hits >= 5, "{hits}");
        // Every point on the person and none of the room.
        assert_eq!(with.rejected, hits, "{with:?}");
        assert!(with.pose.translation().norm() < 1e-4, "{with:?}");
        assert_eq!(without.rejected, 0);
        assert!(
            without.pose.translation().norm() > 10.0 * with.pose.translation().norm().max(1e-4),
            "the person pulls the unrejected estimate: {without:?}"
        );
    }

    #[test]
    fn rejection_keeps_a_moving_lidars_static_scene() {
        // The lidar moved 4 cm along x, as it did the revolution before.
        let step = Vec2::new(0.04, 0.0);
        let reference = scan(Vec2::ZERO, None);
        let current = scan(step, None);
        let rejection = PaperRejection {
            previous: step,
            gain: 4.0,
            floor_m: 0.0,
        };
        let found = fig_4(&reference, &current, Some(rejection));
        assert_eq!(found.rejected, 0, "{found:?}");
        assert!((found.pose.translation() - step).norm() < 0.01, "{found:?}");
    }

    #[test]
    fn coincident_points_define_no_line() {
        assert!(
            closest_point_on_line(Vec2::new(1.0, 1.0), Vec2::new(1.0, 1.0), Vec2::ZERO).is_none()
        );
    }
}
