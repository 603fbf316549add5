//! The pose fix the companion sends for each revolution: the SLAM pose, a covariance built from
//! what the scan match observed, a quality from how much of the scan it explained, and a reset
//! counter that tells the autopilot when the pose jumped.

use plumbline_core::msgs::PoseFix;
use plumbline_slam::{ScanPose, Slam};

/// One-sigma floor added to what the match observed (m, rad). The match covariance is the
/// scan's pose relative to its keyframe, a few millimetres; the keyframe's own place in the map
/// (drift between loop closures, a few centimetres on the surveyed logs) is not in it.
const FLOOR_STD_M: f32 = 0.05;
const FLOOR_STD_RAD: f32 = 0.01;

/// Variance sent along a direction the match did not observe (a corridor's axis), m²: far
/// beyond any autopilot's innovation gate, so the fix is fused across that direction only, and
/// moderate enough that the covariance stays positive definite in f32 at any heading.
const UNOBSERVED_VARIANCE_M2: f32 = 100.0;

/// Covariance of a pose predicted while lost: no direction observed (m², rad²).
const LOST_VARIANCE_M2: f32 = UNOBSERVED_VARIANCE_M2;
const LOST_VARIANCE_RAD2: f32 = 1.0;

/// Why the reset counter went up, counted for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Resets {
    /// A loop closure moved the keyframe under the previous scan.
    pub map_corrections: usize,
    /// Matching again after one or more revolutions lost.
    pub recoveries: usize,
    /// The motion guess fitted badly and a wide search placed the scan instead.
    pub searches: usize,
}

impl Resets {
    pub fn total(&self) -> usize {
        self.map_corrections + self.recoveries + self.searches
    }
}

/// Turns SLAM poses into pose fixes, keeping the reset counter across revolutions.
#[derive(Debug, Default)]
pub struct FixMaker {
    last: Option<ScanPose>,
    searches_seen: usize,
    reset_counter: u8,
    pub resets: Resets,
}

impl FixMaker {
    /// The fix for `at`, the pose `slam` just returned for the revolution stamped `t_s`.
    pub fn fix<const N: usize>(&mut self, slam: &Slam<'_, N>, t_s: f64, at: &ScanPose) -> PoseFix {
        let searches = slam.tracking_stats().guess_searches_used;
        let jumped = [
            (
                &mut self.resets.map_corrections,
                self.last.is_some_and(|last| slam.map_jumped(&last)),
            ),
            (
                &mut self.resets.recoveries,
                self.last.is_some_and(|last| last.predicted) && !at.predicted,
            ),
            (&mut self.resets.searches, searches > self.searches_seen),
        ];
        let mut bumped = false;
        for (count, happened) in jumped {
            *count += usize::from(happened);
            bumped |= happened;
        }
        if bumped {
            self.reset_counter = self.reset_counter.wrapping_add(1);
        }
        self.searches_seen = searches;
        self.last = Some(*at);
        PoseFix {
            t_s,
            position_m: [at.pose.x, at.pose.y],
            yaw_rad: at.pose.theta,
            covariance: covariance(at),
            quality_pct: quality(at),
            reset_counter: self.reset_counter,
        }
    }
}

/// 1 to 100 from the share of the scan the match explained; 0 ("unknown") for the first scan,
/// which has nothing to match and defines the map; `None` (MAVLink -1) when the match failed
/// and the pose is a prediction.
fn quality(at: &ScanPose) -> Option<u8> {
    if at.predicted {
        return None;
    }
    Some(at.observed.map_or(0, |o| {
        (o.inlier_ratio.clamp(0.0, 1.0) * 100.0).round().max(1.0) as u8
    }))
}

/// What the match saw, plus the floor, plus [`UNOBSERVED_VARIANCE_M2`] along a direction it
/// did not see; wide in every direction when lost.
fn covariance(at: &ScanPose) -> [[f32; 3]; 3] {
    let (f, r) = (FLOOR_STD_M * FLOOR_STD_M, FLOOR_STD_RAD * FLOOR_STD_RAD);
    if at.predicted {
        let (l, h) = (LOST_VARIANCE_M2, LOST_VARIANCE_RAD2);
        return [[l, 0.0, 0.0], [0.0, l, 0.0], [0.0, 0.0, h]];
    }
    let mut c = at.observed.map_or([[0.0; 3]; 3], |o| o.seen_covariance);
    for (i, floor) in [f, f, r].into_iter().enumerate() {
        c[i][i] += floor;
    }
    if let Some(d) = at.observed.and_then(|o| o.degenerate_direction) {
        // d[i] * d[j] first: the same bits for (i, j) and (j, i), an exactly symmetric sum.
        let d = [d.x, d.y];
        for (i, row) in c.iter_mut().take(2).enumerate() {
            for (j, v) in row.iter_mut().take(2).enumerate() {
                *v += UNOBSERVED_VARIANCE_M2 * (d[i] * d[j]);
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_core::geom::{Pose2, Vec2};
    use plumbline_slam::Observed;

    fn at(predicted: bool, observed: Option<Observed>) -> ScanPose {
        ScanPose {
            keyframe: None,
            relative: Pose2::IDENTITY,
            pose: Pose2::new(1.0, 2.0, 0.5),
            new_keyframe: false,
            predicted,
            observed,
        }
    }

    fn observed(inlier_ratio: f32, degenerate: Option<Vec2>) -> Observed {
        let seen = [[4e-6, 1e-6, 0.0], [1e-6, 9e-6, 0.0], [0.0, 0.0, 1e-6]];
        Observed {
            covariance: seen,
            seen_covariance: seen,
            degenerate_direction: degenerate,
            inlier_ratio,
        }
    }

    #[test]
    fn quality_follows_the_explained_share_and_is_none_when_lost() {
        assert_eq!(quality(&at(false, Some(observed(0.874, None)))), Some(87));
        assert_eq!(quality(&at(false, Some(observed(0.0, None)))), Some(1));
        assert_eq!(quality(&at(false, Some(observed(1.0, None)))), Some(100));
        assert_eq!(quality(&at(false, None)), Some(0));
        assert_eq!(quality(&at(true, None)), None);
    }

    #[test]
    fn covariance_is_the_seen_part_plus_the_floor_and_unobserved_along_a_corridor() {
        let c = covariance(&at(false, Some(observed(0.9, None))));
        let f = FLOOR_STD_M * FLOOR_STD_M;
        assert_eq!(c[0][0], 4e-6 + f);
        assert_eq!(c[1][1], 9e-6 + f);
        assert_eq!((c[0][1], c[1][0]), (1e-6, 1e-6));
        assert_eq!(c[2][2], 1e-6 + FLOOR_STD_RAD * FLOOR_STD_RAD);
        let along = Vec2::new(0.6, 0.8);
        let c = covariance(&at(false, Some(observed(0.9, Some(along)))));
        let var = |u: Vec2| u.x * u.x * c[0][0] + 2.0 * u.x * u.y * c[0][1] + u.y * u.y * c[1][1];
        assert!(var(along) > UNOBSERVED_VARIANCE_M2, "{c:?}");
        assert!(var(along.perp()) < 0.01, "{c:?}");
        assert_eq!(c[0][1], c[1][0]);
        let lost = covariance(&at(true, None));
        assert_eq!(
            (lost[0][0], lost[2][2]),
            (LOST_VARIANCE_M2, LOST_VARIANCE_RAD2)
        );
    }
}
