//! Odometry with a local map: scan-to-keyframe matching as [`LidarOdometry`] does it, and every
//! new keyframe aligned with the map before it is added to it.

use super::cells::LineMap;
use super::refine::{
    correction_is_plausible, map_age, refine, RefineConfig, RefineRefusal, Refined,
};
use super::relocalize::{relocalize, Declined, RelocalizeConfig};
use crate::geom::Pose2;
use crate::matching::linalg::Sym3;
use crate::matching::{LidarOdometry, MatchResult, OdometryConfig, OdometryStep};
use crate::scan::Scan;

/// What the map did with one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapUse {
    /// Not a keyframe: the pose is the scan matcher's.
    NotKeyframe,
    /// The keyframe was aligned with the map, then added to it.
    Refined(Refined),
    /// The keyframe lined up with walls mapped long ago at a pose the refinement alone could
    /// not reach (the end of a loop); it was moved there, then added.
    Relocalized(Refined),
    /// The map could not align the keyframe; it was added at the scan matcher's pose.
    Refused(RefineRefusal),
    /// The keyframe came from a failed match (a guess), so it was neither aligned nor added.
    Skipped,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MappedStep {
    pub step: OdometryStep,
    pub map: MapUse,
    /// The relocalization search, when one ran for this scan.
    pub search: Option<Result<Pose2, Declined>>,
}

pub struct MappedOdometry<'m, const N: usize> {
    odometry: LidarOdometry<N>,
    map: LineMap<'m>,
    refine: RefineConfig,
    relocalize: Option<RelocalizeConfig>,
    /// A jump the last search proposed, as the world transform from the drifted pose to the
    /// found one, waiting for the next search to propose the same before it is made.
    pending_jump: Option<Pose2>,
}

impl<'m, const N: usize> MappedOdometry<'m, N> {
    pub fn new(
        config: OdometryConfig,
        map: LineMap<'m>,
        refine: RefineConfig,
        relocalize: Option<RelocalizeConfig>,
    ) -> Self {
        Self {
            odometry: LidarOdometry::new(config),
            map,
            refine,
            relocalize,
            pending_jump: None,
        }
    }

    pub fn pose(&self) -> Pose2 {
        self.odometry.pose()
    }

    pub fn map(&self) -> &LineMap<'m> {
        &self.map
    }

    pub fn update(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> MappedStep {
        let previous_keyframe = self.odometry.keyframe_pose();
        let step = self.odometry.update(scan, prior);
        if !step.took_keyframe() {
            return MappedStep {
                step,
                map: MapUse::NotKeyframe,
                search: None,
            };
        }
        let (map, search) = match step {
            OdometryStep::Started => {
                self.add_keyframe();
                let first = Refined {
                    pose: self.odometry.pose(),
                    matched: 0,
                    iterations: 0,
                };
                (MapUse::Refined(first), None)
            }
            OdometryStep::Matched { result, .. } => self.align_keyframe(&result, previous_keyframe),
            OdometryStep::Predicted { .. } => (MapUse::Skipped, None),
        };
        MappedStep { step, map, search }
    }

    fn align_keyframe(
        &mut self,
        result: &MatchResult,
        previous_keyframe: Pose2,
    ) -> (MapUse, Option<Result<Pose2, Declined>>) {
        let now = self.odometry.keyframes_taken();
        let points = self.odometry.keyframe_points();
        let search = self
            .relocalize
            .as_ref()
            .filter(|r| {
                r.every_keyframes > 0
                    && (self.pending_jump.is_some() || now.is_multiple_of(r.every_keyframes))
            })
            .map(|r| relocalize(&self.map, points, self.odometry.pose(), now, r));
        // A pose the search found counts only if it is a real jump (near the guess the
        // refinement does better on its own), if the search at the next keyframe proposes the
        // same jump (a wrong fit in clutter rarely repeats, a drift does), and once the
        // refinement, with no prior but the map, confirms it off the search's grid.
        let guess = self.odometry.pose();
        let proposed = search
            .and_then(Result::ok)
            .zip(self.relocalize.as_ref())
            .filter(|(found, r)| {
                let (shift, turn) = guess.distance_to(*found);
                shift > r.min_jump_m || turn > r.min_jump_rad
            });
        let confirmed = proposed.filter(|(found, r)| {
            self.pending_jump.is_some_and(|jump| {
                let (shift, turn) = jump.compose(guess).distance_to(*found);
                shift <= r.min_jump_m && turn <= r.min_jump_rad
            })
        });
        self.pending_jump = match confirmed {
            Some(_) => None,
            None => proposed.map(|(found, _)| found.compose(guess.inverse())),
        };
        let relocalized = confirmed.and_then(|(found, _)| {
            refine(&self.map, points, found, Sym3::default(), &self.refine).ok()
        });
        let used = match relocalized {
            Some(refined) => MapUse::Relocalized(refined),
            None => {
                let outcome = information_in_world(&result.covariance, previous_keyframe.theta)
                    .ok_or(RefineRefusal::Diverged)
                    .and_then(|information| {
                        let prior = information.scaled(self.refine.matcher_weight);
                        let refined = refine(&self.map, points, guess, prior, &self.refine)?;
                        let age = map_age(&self.map, points, guess, now, self.refine.gate_m);
                        correction_is_plausible(
                            guess,
                            refined.pose,
                            &information,
                            age.unwrap_or(1.0),
                            self.refine.max_correction_d2,
                        )?;
                        Ok(refined)
                    });
                match outcome {
                    Ok(refined) => MapUse::Refined(refined),
                    Err(refusal) => MapUse::Refused(refusal),
                }
            }
        };
        if let MapUse::Refined(r) | MapUse::Relocalized(r) = used {
            self.odometry.reanchor_keyframe(r.pose);
        }
        self.add_keyframe();
        (used, search)
    }

    fn add_keyframe(&mut self) {
        let pose = self.odometry.pose();
        let stamp = self.odometry.keyframes_taken();
        for &p in self.odometry.keyframe_points() {
            self.map.insert(pose.transform(p), stamp);
        }
    }
}

/// The scan matcher's information (inverse covariance of the motion in the previous keyframe's
/// frame) re-expressed for a world-frame pose: `B Λ Bᵀ` with `B = diag(R(heading), 1)`.
fn information_in_world(covariance: &[[f32; 3]; 3], heading: f32) -> Option<Sym3> {
    let m = Sym3::from_array(*covariance).inverse()?;
    let (s, c) = (libm::sinf(heading), libm::cosf(heading));
    Some(Sym3 {
        xx: (c * c * m.xx - 2.0 * c * s * m.xy + s * s * m.yy),
        xy: (c * s * (m.xx - m.yy) + (c * c - s * s) * m.xy),
        yy: (s * s * m.xx + 2.0 * c * s * m.xy + c * c * m.yy),
        xt: (c * m.xt - s * m.yt),
        yt: (s * m.xt + c * m.yt),
        tt: m.tt,
    })
}
