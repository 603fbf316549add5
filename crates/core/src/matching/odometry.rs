//! Lidar-only odometry: chains scan matches into a pose, the way the vehicle uses it in flight.
//!
//! Each scan is matched against a keyframe rather than the scan just before it, so while the
//! vehicle stays near a keyframe its error does not grow scan by scan; a new keyframe is taken
//! once the vehicle has moved far enough that overlap starts to suffer. The initial guess is a
//! caller's prior (wheel odometry, IMU) or, lidar-only, the last motion repeated.
//!
//! When matches fail one after another the last motion is not repeated for ever: a lidar that
//! stops returning (spinning down, covered, blinded) says nothing about the vehicle still moving,
//! and repeating a last, possibly bad, motion turns a standing sensor into a spinning one. Each
//! failed scan in a row carries the pose forward by a shrinking fraction of the last motion
//! ([`OdometryConfig::lost_motion_decay`]), so however long the sensor stays lost the predicted
//! pose moves at most `1 / (1 - decay)` times the last motion, and comes to rest.
//!
//! A match that converged can still be wrong: when the matcher's recovery search restarts it
//! from a pose of its own (a poor fit from the prediction), it can settle tenths of a metre
//! away along walls that barely constrain it. Such a match is checked against what the vehicle
//! can have done since the last scan that matched ([`MotionLimits`]): a pose farther from the
//! prediction than that acceleration allows is refused, bridged by the prediction like a
//! failed match, and counted. Matches made from the prediction itself are not checked: with
//! lidar alone the prediction is the last motion repeated, and refusing a good match for
//! disagreeing with it keeps the stale motion (on the simulated XV-11 surveys that flew the
//! estimate metres off, and Intel lost 37 good scans).

use super::linalg::Sym3;
use super::prior_fusion::{self, PriorFusion};
use super::{MatchConfig, MatchError, MatchResult, ScanMatcher};
use crate::geom::{Pose2, Vec2};
use crate::scan::Scan;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryConfig {
    pub matcher: MatchConfig,
    /// Take a new keyframe after moving this far from the current one, m.
    pub keyframe_distance_m: f32,
    /// …or turning this much, rad.
    pub keyframe_angle_rad: f32,
    /// …or when fewer than this fraction of points still find a partner in it…
    pub keyframe_min_inlier_ratio: f32,
    /// …or when the match was constrained this unevenly or worse (its `conditioning`, least
    /// over most translational information) and the next scan, if the vehicle keeps moving as
    /// over the last interval, would lie farther than `keyframe_reach_m` from the keyframe.
    /// In a corridor the motion along it rests on a few wall ends; with scans far apart (a slow
    /// scan rate, a fast vehicle, a thinned log) the next one would be matched a keyframe
    /// spacing plus a whole step away, where those ends pair with the wrong neighbours and the
    /// match slides along the corridor. Taking the keyframe a scan early keeps such matches
    /// within the reach; where walls run both ways the match holds farther out and no extra
    /// keyframe is paid for. A conditioning of 0 or a reach of infinity: off.
    pub keyframe_reach_below_conditioning: f32,
    /// The reach above, m.
    pub keyframe_reach_m: f32,
    /// While lost (matches failing in a row, no prior), each failed scan moves the pose by this
    /// fraction of the motion used for the one before; the first failed scan by the whole last
    /// motion. In [0, 1): 0 stops at once, 0.5 bounds the whole excursion to twice the last motion.
    pub lost_motion_decay: f32,
    /// What the vehicle can do between scans; a match beyond it is refused. `None` (the
    /// default): no check. The log commands (`odometry`, `slam`) turn it on; the onboard stack
    /// leaves it off, because it has been measured on logs and surveys but not in flight, where
    /// it moved the simulated flights without a measured gain.
    pub motion_limits: Option<MotionLimits>,
    /// How a caller's prior is combined with each match ([`prior_fusion`]). `None` (the
    /// default): the prior is only the match's starting guess, and the match decides every
    /// direction it observed. Flights and the logs without a prior leave it off.
    pub prior_fusion: Option<PriorFusion>,
}

/// How far a vehicle can stray from the predicted motion (the prior, or the last motion
/// repeated) in `dt` seconds: `floor + accel * dt² / 2`, in metres and radians. The floor holds
/// what the prediction itself gets wrong (a noisy last motion, a prior's error).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    pub floor_m: f32,
    pub accel_m_s2: f32,
    pub floor_rad: f32,
    pub accel_rad_s2: f32,
}

impl Default for MotionLimits {
    /// Generous for an indoor quadcopter or a ground robot (3 m/s², 10 rad/s²), with a floor
    /// of 5 cm and 0.05 rad for the prediction's own error.
    fn default() -> Self {
        Self {
            floor_m: 0.05,
            accel_m_s2: 3.0,
            floor_rad: 0.05,
            accel_rad_s2: 10.0,
        }
    }
}

impl MotionLimits {
    /// Whether a pose `shift_m` and `turn_rad` away from the prediction made `dt_s` after the
    /// last matched scan is within reach. A gap that is not a positive finite time (a log
    /// without usable stamps) allows anything.
    pub fn allows(&self, shift_m: f32, turn_rad: f32, dt_s: f32) -> bool {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return true;
        }
        let reach = |floor: f32, accel: f32| floor + 0.5 * accel * dt_s * dt_s;
        shift_m <= reach(self.floor_m, self.accel_m_s2)
            && turn_rad <= reach(self.floor_rad, self.accel_rad_s2)
    }
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            matcher: MatchConfig::default(),
            keyframe_distance_m: 0.3,
            keyframe_angle_rad: 0.25,
            keyframe_min_inlier_ratio: 0.6,
            keyframe_reach_below_conditioning: 0.0,
            keyframe_reach_m: f32::INFINITY,
            lost_motion_decay: 0.5,
            motion_limits: None,
            prior_fusion: None,
        }
    }
}

impl OdometryConfig {
    /// The odometry as the onboard stack flies it: the defaults, with the matcher's recovery
    /// search resting for three matches after a search a low inlier ratio alone started found
    /// nothing better ([`MatchConfig::recovery_rest_matches`]). Over the simulated exploration
    /// flights (seeds 1-200, three worlds) every count stayed within its spread, and the
    /// slowest Intel flights took a fifth to a half less CPU.
    pub fn in_flight() -> Self {
        let mut config = Self::default();
        config.matcher.recovery_rest_matches = 3;
        config
    }
}

/// What one scan did to the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OdometryStep {
    /// The first usable scan: it became the first keyframe at the origin.
    Started,
    /// Matched; the pose is updated from the match.
    Matched {
        result: MatchResult,
        new_keyframe: bool,
    },
    /// The match failed; the pose was carried forward by the prediction alone (a decaying one
    /// when failures follow each other): the pose at this scan is not a measurement.
    Predicted {
        error: MatchError,
        /// This scan became the keyframe, so one bad keyframe cannot stall the odometry; it
        /// does not when the scan itself was unusable.
        restarted: bool,
    },
}

impl OdometryStep {
    /// Whether this scan became the keyframe the next scans are matched against.
    pub fn took_keyframe(&self) -> bool {
        match *self {
            Self::Started => true,
            Self::Matched { new_keyframe, .. } => new_keyframe,
            Self::Predicted { restarted, .. } => restarted,
        }
    }
}

#[derive(Clone, Debug)]
pub struct LidarOdometry<const N: usize> {
    config: OdometryConfig,
    matcher: ScanMatcher<N>,
    keyframe_pose: Pose2,
    pose: Pose2,
    /// Motion over the last scan interval, the lidar-only prediction for the next one; shrunk by
    /// `lost_motion_decay` after each failed match.
    last_motion: Pose2,
    keyframes_taken: u32,
    /// Stamp of the last scan whose match was taken, s.
    last_matched_s: f64,
    /// Matches refused by [`MotionLimits`] so far.
    implausible: u32,
    /// Covariance of the pose relative to the keyframe under [`OdometryConfig::prior_fusion`]
    /// (zero at a keyframe, and while no prior is fused).
    relative_covariance: Sym3,
}

impl<const N: usize> LidarOdometry<N> {
    pub fn new(config: OdometryConfig) -> Self {
        Self {
            config,
            matcher: ScanMatcher::new(config.matcher),
            keyframe_pose: Pose2::IDENTITY,
            pose: Pose2::IDENTITY,
            last_motion: Pose2::IDENTITY,
            keyframes_taken: 0,
            last_matched_s: f64::NAN,
            implausible: 0,
            relative_covariance: Sym3::default(),
        }
    }

    /// Pose of the current keyframe in the frame of the first scan.
    pub fn keyframe_pose(&self) -> Pose2 {
        self.keyframe_pose
    }

    /// How many keyframes have been taken so far: a clock that ticks once a keyframe, by which
    /// the local map tells old walls from new.
    pub fn keyframes_taken(&self) -> u32 {
        self.keyframes_taken
    }

    /// The current keyframe's points in its own frame.
    pub fn keyframe_points(&self) -> &[Vec2] {
        self.matcher.reference_points()
    }

    /// Moves the keyframe just taken (and so the current pose) to where another source, such as
    /// a map, places it better. Call it only right after an update that took a keyframe.
    pub fn reanchor_keyframe(&mut self, pose: Pose2) {
        self.keyframe_pose = pose;
        self.pose = pose;
    }

    /// How many matches were refused as beyond what the motion can do (see [`MotionLimits`]).
    pub fn implausible_matches(&self) -> u32 {
        self.implausible
    }

    /// Current pose estimate in the frame of the first scan.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Feeds the next revolution; `prior` is the motion since the previous scan from another
    /// source, if there is one.
    pub fn update(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> OdometryStep {
        if !self.matcher.has_reference() {
            return match self.matcher.set_reference(scan) {
                Ok(()) => {
                    self.last_matched_s = scan.stamp_s;
                    self.keyframe_pose = self.pose;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                    OdometryStep::Started
                }
                Err(error) => OdometryStep::Predicted {
                    error,
                    restarted: false,
                },
            };
        }
        let prior = prior.filter(|p| p.is_finite());
        let predicted_motion = prior.unwrap_or(self.last_motion);
        let predicted = self.pose.compose(predicted_motion);
        let guess = self.keyframe_pose.between(predicted);
        let dt_s = (scan.stamp_s - self.last_matched_s) as f32;
        let fusion = self.config.prior_fusion.zip(prior).map(|(fusion, motion)| {
            let from = self.keyframe_pose.between(self.pose);
            let covariance =
                prior_fusion::predict(&fusion, from, &self.relative_covariance, motion);
            (fusion, covariance)
        });
        self.relative_covariance = fusion.map_or(Sym3::default(), |(_, c)| c);
        let matched = self.matcher.match_scan(scan, guess).and_then(|result| {
            let (shift, turn) = predicted.distance_to(self.keyframe_pose.compose(result.motion));
            match self.config.motion_limits {
                Some(limits) if result.quality.recovered && !limits.allows(shift, turn, dt_s) => {
                    self.implausible = self.implausible.saturating_add(1);
                    Err(MatchError::Implausible {
                        shift_m: shift,
                        turn_rad: turn,
                    })
                }
                _ => Ok(result),
            }
        });
        match matched {
            Ok(mut result) => {
                if let Some((pose, covariance)) = fusion.and_then(|(fusion, covariance)| {
                    prior_fusion::fuse(&fusion, guess, &covariance, &result)
                }) {
                    result.motion = pose;
                    self.relative_covariance = covariance;
                }
                self.last_matched_s = scan.stamp_s;
                let new_pose = self.keyframe_pose.compose(result.motion);
                self.last_motion = self.pose.between(new_pose);
                self.pose = new_pose;
                let (dist, angle) = self.keyframe_pose.distance_to(new_pose);
                let beyond_reach = || {
                    let next = new_pose.compose(self.last_motion);
                    result.quality.conditioning < self.config.keyframe_reach_below_conditioning
                        && self.keyframe_pose.distance_to(next).0 > self.config.keyframe_reach_m
                };
                let new_keyframe = dist > self.config.keyframe_distance_m
                    || angle > self.config.keyframe_angle_rad
                    || result.quality.inlier_ratio < self.config.keyframe_min_inlier_ratio
                    || beyond_reach();
                if new_keyframe {
                    self.matcher.promote_current();
                    self.relative_covariance = Sym3::default();
                    self.keyframe_pose = new_pose;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                }
                OdometryStep::Matched {
                    result,
                    new_keyframe,
                }
            }
            Err(error) => {
                self.pose = predicted;
                // A refused match says the scan fitted somewhere it cannot be, not that the
                // vehicle stopped: the motion carries on undecayed, against the same keyframe.
                if !matches!(error, MatchError::Implausible { .. }) {
                    self.last_motion = fraction_of(self.last_motion, self.lost_decay());
                }
                let restarted = !matches!(
                    error,
                    MatchError::TooFewPoints { .. }
                        | MatchError::BeamsNotInAngularOrder { .. }
                        | MatchError::Implausible { .. }
                ) && self.matcher.set_reference(scan).is_ok();
                if restarted {
                    self.relative_covariance = Sym3::default();
                    self.keyframe_pose = predicted;
                    self.keyframes_taken = self.keyframes_taken.wrapping_add(1);
                }
                OdometryStep::Predicted { error, restarted }
            }
        }
    }

    /// The configured decay, kept in [0, 1) so that a bad value cannot make the prediction grow.
    fn lost_decay(&self) -> f32 {
        let d = self.config.lost_motion_decay;
        if d.is_finite() {
            d.clamp(0.0, MAX_LOST_DECAY)
        } else {
            0.0
        }
    }
}

/// The largest decay accepted: below 1 so that the excursion while lost stays bounded.
const MAX_LOST_DECAY: f32 = 0.95;

/// `k` times a small motion, component by component (for the few-degree motions between scans
/// this is the motion at `k` times the speed, which is all a decaying prediction needs).
fn fraction_of(motion: Pose2, k: f32) -> Pose2 {
    Pose2::new(motion.x * k, motion.y * k, motion.theta * k)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::matching::PriorFusion;
    use crate::scan::Beam;

    /// A scan with too few valid beams to match: what a lidar spinning down or covered sends.
    fn blind_scan(stamp_s: f64) -> Scan<360> {
        let mut scan = Scan::new(stamp_s);
        for k in 0..360 {
            let beam = if k < 5 {
                Beam::new((k as f32).to_radians(), 2.0)
            } else {
                Beam::invalid((k as f32).to_radians())
            };
            scan.push(beam).unwrap();
        }
        scan
    }

    #[test]
    fn a_lost_sensor_comes_to_rest_within_a_bounded_excursion() {
        for decay in [0.0f32, 0.5, 0.9, 2.0, f32::NAN] {
            let config = OdometryConfig {
                lost_motion_decay: decay,
                ..OdometryConfig::default()
            };
            let mut odometry = LidarOdometry::<360>::new(config);
            // As if the last match had turned 0.5 rad and moved 0.1 m: the worst kind of last
            // motion to repeat.
            odometry.last_motion = Pose2::new(0.1, 0.0, 0.5);
            odometry.matcher.set_reference(&room(0.0)).unwrap();
            let mut turned = 0.0f32;
            let mut last_step = f32::INFINITY;
            for k in 0..200 {
                let before = odometry.pose();
                let step = odometry.update(&blind_scan(1.0 + k as f64 * 0.1), None);
                assert!(matches!(step, OdometryStep::Predicted { .. }));
                let step_turn = before.between(odometry.pose()).theta.abs();
                assert!(step_turn <= last_step + 1e-6, "the prediction never grows");
                last_step = step_turn;
                turned += step_turn;
            }
            let bound = 0.5
                / (1.0
                    - if decay.is_finite() {
                        decay.clamp(0.0, MAX_LOST_DECAY)
                    } else {
                        0.0
                    });
            assert!(
                turned <= bound + 1e-4,
                "decay {decay}: turned {turned} rad, bound {bound}"
            );
            assert!(
                last_step < 1e-3,
                "decay {decay}: still turning {last_step} rad a scan"
            );
        }
    }

    #[test]
    fn the_motion_limits_reach_grows_with_the_gap_and_a_bad_gap_limits_nothing() {
        let limits = MotionLimits::default();
        // 0.25 s (one XV-11 revolution): 5 cm + 3 m/s² * 0.25² / 2 = 14.4 cm.
        assert!(limits.allows(0.14, 0.0, 0.25));
        assert!(!limits.allows(0.15, 0.0, 0.25));
        assert!(!limits.allows(0.0, 0.40, 0.25));
        // A gap of a second reaches 1.55 m and 5.05 rad.
        assert!(limits.allows(1.5, 0.40, 1.0));
        for dt in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(limits.allows(100.0, 100.0, dt), "dt {dt}");
        }
    }

    #[test]
    fn one_failed_scan_is_bridged_by_the_whole_last_motion() {
        let mut odometry = LidarOdometry::<360>::new(OdometryConfig::default());
        odometry.matcher.set_reference(&room(0.0)).unwrap();
        odometry.last_motion = Pose2::new(0.05, 0.0, 0.02);
        odometry.update(&blind_scan(1.0), None);
        let p = odometry.pose();
        assert!(
            (p.x - 0.05).abs() < 1e-6 && (p.theta - 0.02).abs() < 1e-6,
            "{p:?}"
        );
    }

    #[test]
    fn a_keyframe_is_taken_a_scan_early_only_when_the_next_would_be_out_of_reach() {
        // Moving 0.2 m a scan, keyframes every 0.3 m: the second scan would be matched 0.4 m
        // from the first keyframe. A reach of 0.35 m takes the keyframe at the first scan, but
        // only for matches conditioned below the gate (a box's always are, below 1.01).
        for (gate, reach, early) in [
            (0.0, f32::INFINITY, false),
            (1.01, 0.35, true),
            (1.01, 0.45, false),
            (0.0, 0.35, false),
        ] {
            let config = OdometryConfig {
                keyframe_reach_below_conditioning: gate,
                keyframe_reach_m: reach,
                ..OdometryConfig::default()
            };
            let mut odometry = LidarOdometry::<360>::new(config);
            assert_eq!(
                odometry.update(&room_at(0.0, 0.0), None),
                OdometryStep::Started
            );
            // The prior is the true motion: the test is about the keyframe, not the match.
            let step = odometry.update(&room_at(0.2, 0.0), Some(Pose2::new(0.2, 0.0, 0.0)));
            let OdometryStep::Matched { new_keyframe, .. } = step else {
                panic!("the box should match: {step:?}");
            };
            assert_eq!(new_keyframe, early, "gate {gate}, reach {reach}");
            assert!(
                (odometry.pose().x - 0.2).abs() < 0.01,
                "{:?}",
                odometry.pose()
            );
        }
    }

    /// A 360-beam scan of a bare corridor 2 m wide along x, taken from (`x`, `y`) facing
    /// along it turned by `theta`, by a lidar of 4 m range (nothing measures x), with ranges
    /// perturbed by up to `noise_m` (a fixed pseudo-random sequence seeded by `seed`).
    fn corridor_at(x: f32, y: f32, theta: f32, noise_m: f32, seed: u32) -> Scan<360> {
        let _ = x; // the corridor looks the same from everywhere along it
        let mut state = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let mut scan = Scan::new(0.0);
        for k in 0..360 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let jitter = ((state >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 2.0 * noise_m;
            let a = (k as f32).to_radians();
            let s = libm::sinf(a + theta);
            let r = if s > 1e-6 {
                (1.0 - y) / s
            } else if s < -1e-6 {
                (1.0 + y) / -s
            } else {
                f32::INFINITY
            };
            let beam = if r < 4.0 {
                Beam::new(a, r + jitter)
            } else {
                Beam::invalid(a)
            };
            scan.push(beam).unwrap();
        }
        scan
    }

    #[test]
    fn a_fused_prior_decides_along_a_bare_corridor_and_the_lidar_across_it() {
        // The vehicle moves 0.2 m a scan along the corridor, drifting 1 cm a scan towards one
        // wall, and turns 0.5 mrad a scan. The prior is the true motion with the errors of a
        // poor odometry across (2 cm a scan to the side) and in heading (5 mrad a scan).
        let matcher = MatchConfig {
            localizability_check_below: 0.25,
            ..MatchConfig::default()
        };
        let fusion = PriorFusion::new(0.02, 0.0, 0.005, 0.0);
        let run = |prior_fusion: Option<PriorFusion>| {
            let config = OdometryConfig {
                matcher,
                prior_fusion,
                ..OdometryConfig::default()
            };
            let mut odometry = LidarOdometry::<360>::new(config);
            let mut degenerate = 0;
            for k in 0..12u32 {
                let t = k as f32;
                let scan = corridor_at(0.2 * t, 0.01 * t, 0.0005 * t, 0.01, k);
                let prior = Pose2::new(0.2, 0.01 - 0.02, 0.0005 + 0.005);
                if let OdometryStep::Matched { result, .. } = odometry.update(&scan, Some(prior)) {
                    degenerate += result.quality.degenerate_direction.is_some() as usize;
                }
            }
            (odometry.pose(), degenerate)
        };
        let truth = Pose2::new(0.2 * 11.0, 0.01 * 11.0, 0.0005 * 11.0);
        let (fused, degenerate) = run(Some(fusion));
        assert!(
            degenerate >= 10,
            "the corridor should be degenerate: {degenerate}"
        );
        // Along the corridor only the prior measures: 11 steps of 0.2 m, as it said.
        assert!((fused.x - truth.x).abs() < 0.005, "{fused:?} vs {truth:?}");
        // Across and in heading the lidar corrects the prior's drift (0.22 m, 0.055 rad).
        assert!((fused.y - truth.y).abs() < 0.02, "{fused:?} vs {truth:?}");
        assert!(
            (fused.theta - truth.theta).abs() < 0.01,
            "{fused:?} vs {truth:?}"
        );
        // The match alone starts from the same prior but lets its point-to-point passes move
        // the pose along the corridor's axis, where they measure nothing (2 cm here).
        let (alone, _) = run(None);
        assert!((alone.x - truth.x).abs() > 0.015, "{alone:?} vs {truth:?}");
    }

    /// A 360-beam scan of a 6 m x 4 m box taken from its centre, turned by `theta`.
    fn room(theta: f32) -> Scan<360> {
        room_at(0.0, theta)
    }

    /// The same box seen from `x` m along its long axis.
    fn room_at(x: f32, theta: f32) -> Scan<360> {
        let mut scan = Scan::new(0.0);
        for k in 0..360 {
            let a = (k as f32).to_radians();
            let (s, c) = libm::sincosf(a + theta);
            let wx = if c > 1e-6 {
                (3.0 - x) / c
            } else if c < -1e-6 {
                (3.0 + x) / -c
            } else {
                f32::INFINITY
            };
            let wy = if s.abs() > 1e-6 {
                2.0 / s.abs()
            } else {
                f32::INFINITY
            };
            scan.push(Beam::new(a, wx.min(wy))).unwrap();
        }
        scan
    }
}
