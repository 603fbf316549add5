//! Companion pose fix: an absolute (x, y, yaw) measurement from the companion computer's SLAM.
//!
//! How it combines with the onboard lidar odometry: the odometry (keyframe scan matching,
//! [`super::scan_match`]) measures *relative* motion at every revolution and keeps the hold
//! stiff, but its errors add up; the fix measures the pose in the companion's map, whose loop
//! closures and submaps do not drift, at whatever rate the companion manages. Both go through
//! the same gated EKF update, so the fix slowly pulls the odometry's drift out of the estimate
//! while the odometry carries the short term. Both see the same scans, so their errors are
//! correlated; the fix's covariance is inflated by [`PoseFixConfig::covariance_scale`] rather
//! than fused as if independent.
//!
//! Frames. The companion's map frame need not be the autopilot's world frame: a fix is mapped
//! through an *anchor* (map -> world) before fusion, and the companion's setpoints go through
//! the same anchor. The first accepted fix sets the anchor so that it agrees with the current
//! estimate, and so does every change of the fix's `reset_counter` (the companion re-localised
//! and its pose jumped): the estimate is never yanked by a jump, and the fixes after it
//! correct the estimate relative to the new anchor. A fix that disagrees with the estimate
//! without a reset is refused by the gate for as long as it disagrees, and counted: re-anchoring
//! on it would silently give up the map's correction of the odometry's drift, so a companion
//! must bump `reset_counter` whenever its pose jumps.
//!
//! A fix is fused with its full covariance, gated by its Mahalanobis distance under it. A SLAM
//! in a featureless corridor knows its position across the corridor but not along it, and says
//! so by a position covariance that is wide along the axis only: wider than
//! `max_position_std_m` in one direction, the fix is fused across that direction (and in
//! heading) only, so the odometry and the IMU keep the axis, and a made-up position along it
//! never pins the estimate. The onboard scan matcher's degenerate axis is handled the same way
//! ([`super::scan_match`]).
//!
//! Refused without touching the filter, and counted: a non-finite value, a covariance that is
//! not symmetric positive definite or that is wider than the configured bounds in heading or
//! in every direction of position, a lost or low-quality fix, and a fix older than
//! `max_latency_s`.

use super::ekf::{ix, Ekf, Outcome, N};
use crate::geom::{normalize_angle, Pose2, Vec2};
use crate::matching::linalg::sym2_eigen;
use crate::msgs::PoseFix;
use libm::{cosf, sinf};
use nalgebra::{Matrix2x3, Matrix3, SMatrix, Vector3};

/// Settings of the companion pose fusion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseFixConfig {
    /// Fixes of lower quality (0-100) are refused. 0 takes every fix that is not lost.
    pub min_quality_pct: u8,
    /// Fixes whose heading one-sigma (rad) exceeds this, or whose position one-sigma (m)
    /// exceeds this in every direction, are refused: a map pose that unsure says nothing the
    /// odometry does not. Wider in one direction only, the position along it is not fused.
    pub max_position_std_m: f32,
    pub max_yaw_std_rad: f32,
    /// Factor on the fix's covariance: the SLAM and the onboard odometry match the same scans,
    /// so their errors are correlated and the fix must not count as independent evidence.
    pub covariance_scale: f32,
    /// Fixes older than this (s) when they arrive, or from further in the future (a companion
    /// clock gone wrong), are refused; the others are compared with the pose taken back along
    /// the velocity by their age.
    pub max_latency_s: f32,
}

impl Default for PoseFixConfig {
    fn default() -> Self {
        Self {
            min_quality_pct: 20,
            max_position_std_m: 1.0,
            max_yaw_std_rad: 0.3,
            covariance_scale: 4.0,
            max_latency_s: 0.5,
        }
    }
}

/// What became of the pose fixes so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoseFixCounters {
    /// Fused into the EKF.
    pub accepted: u32,
    /// Failed the EKF's innovation gate.
    pub rejected: u32,
    /// Non-finite values or a covariance that is not symmetric positive definite or too wide.
    pub invalid: u32,
    /// Lost (no quality) or below `min_quality_pct`.
    pub low_quality: u32,
    /// Timed more than `max_latency_s` from their arrival, either way.
    pub late: u32,
    /// Times the map frame was (re-)anchored: the first fix and each `reset_counter` change.
    pub anchors: u32,
    /// Fixes whose position went to the EKF across one direction only, the other being wider
    /// than `max_position_std_m` (a corridor's axis); also counted as accepted or rejected.
    pub one_direction: u32,
}

/// What one fix did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FixOutcome {
    /// Went through the EKF's gated update with this outcome.
    Fused(Outcome),
    /// Set the anchor (first fix or a re-localisation); the state is unchanged.
    Anchored,
    /// Refused before the filter (counted as invalid, low quality or late).
    Refused,
}

/// The companion's map frame as the autopilot sees it: the anchor and the reset counter it
/// belongs to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompanionFrame {
    /// Map -> world; identity until the first fix.
    map_to_world: Pose2,
    /// The `reset_counter` the anchor was set for; `None` until the first fix.
    reset_counter: Option<u8>,
    counters: PoseFixCounters,
}

impl CompanionFrame {
    pub fn counters(&self) -> &PoseFixCounters {
        &self.counters
    }

    /// Map -> world: where the companion's map frame sits in the autopilot's world frame.
    pub fn map_to_world(&self) -> Pose2 {
        self.map_to_world
    }

    /// Checks, anchors or fuses one fix that arrived `age_s` after its time.
    pub fn fuse(
        &mut self,
        ekf: &mut Ekf,
        c: &PoseFixConfig,
        fix: &PoseFix,
        age_s: f32,
    ) -> FixOutcome {
        let count = |n: &mut u32| *n = n.saturating_add(1);
        let Some((covariance, measured)) = well_formed(c, fix) else {
            count(&mut self.counters.invalid);
            return FixOutcome::Refused;
        };
        if fix
            .quality_pct
            .is_none_or(|q| q < c.min_quality_pct || q > 100)
        {
            count(&mut self.counters.low_quality);
            return FixOutcome::Refused;
        }
        if age_s.is_nan() || age_s.abs() > c.max_latency_s {
            count(&mut self.counters.late);
            return FixOutcome::Refused;
        }
        let latency_s = age_s.max(0.0);
        let map_pose = Pose2::new(fix.position_m[0], fix.position_m[1], fix.yaw_rad);
        if self.reset_counter != Some(fix.reset_counter) {
            // The estimate at the fix's time, seen from the fix: the anchor that makes them agree.
            let x = ekf.state();
            let here = Pose2::new(
                x[ix::POS] - latency_s * x[ix::VEL],
                x[ix::POS + 1] - latency_s * x[ix::VEL + 1],
                x[ix::YAW],
            );
            self.map_to_world = here.compose(map_pose.inverse());
            self.reset_counter = Some(fix.reset_counter);
            count(&mut self.counters.anchors);
            return FixOutcome::Anchored;
        }
        let world = self.map_to_world.compose(map_pose);
        let (s, co) = (sinf(self.map_to_world.theta), cosf(self.map_to_world.theta));
        let rotate = Matrix3::new(co, -s, 0.0, s, co, 0.0, 0.0, 0.0, 1.0);
        let r = rotate * covariance * rotate.transpose() * c.covariance_scale;
        let outcome = match measured {
            Measured::Pose => ekf.fuse_pose(world, r, latency_s),
            Measured::Across(across) => {
                count(&mut self.counters.one_direction);
                let across = self.map_to_world.rotate(across);
                ekf.fuse_pose_across(world, r, across, latency_s)
            }
        };
        match outcome {
            Outcome::Accepted => count(&mut self.counters.accepted),
            Outcome::Rejected => count(&mut self.counters.rejected),
            Outcome::Invalid => count(&mut self.counters.invalid),
        }
        FixOutcome::Fused(outcome)
    }

    /// A companion map point in the world frame.
    pub fn to_world(&self, p: [f32; 2]) -> [f32; 2] {
        let w = self.map_to_world.transform(Vec2::new(p[0], p[1]));
        [w.x, w.y]
    }

    /// A world point in the companion's map frame.
    pub fn to_map(&self, p: [f32; 2]) -> [f32; 2] {
        let m = self.map_to_world.inverse().transform(Vec2::new(p[0], p[1]));
        [m.x, m.y]
    }

    /// A companion map direction (a velocity) in the world frame.
    pub fn rotate_to_world(&self, v: [f32; 2]) -> [f32; 2] {
        let w = self.map_to_world.rotate(Vec2::new(v[0], v[1]));
        [w.x, w.y]
    }

    /// A companion map heading in the world frame.
    pub fn yaw_to_world(&self, yaw_rad: f32) -> f32 {
        normalize_angle(yaw_rad + self.map_to_world.theta)
    }
}

/// What of its position a well-formed fix measures.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measured {
    /// Both directions.
    Pose,
    /// Only along this unit direction (map frame): across it the fix is wider than the bound.
    Across(Vec2),
}

/// The fix's covariance and what it measures, if every value is finite, the covariance is
/// symmetric positive definite, its heading within the bound and its position within the bound
/// in at least one direction.
fn well_formed(c: &PoseFixConfig, fix: &PoseFix) -> Option<(Matrix3<f32>, Measured)> {
    let m = Matrix3::from_fn(|i, j| fix.covariance[i][j]);
    let finite = m.iter().all(|v| v.is_finite())
        && fix.position_m.iter().all(|v| v.is_finite())
        && fix.yaw_rad.is_finite();
    let symmetric = (m - m.transpose()).abs().max() <= 1e-6 * m.abs().max();
    if !(finite && symmetric && m.cholesky().is_some()) {
        return None;
    }
    let (max_p2, max_y) = (
        c.max_position_std_m * c.max_position_std_m,
        c.max_yaw_std_rad,
    );
    let (widest, narrowest, narrow) = sym2_eigen(m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let measured = if widest <= max_p2 {
        Measured::Pose
    } else {
        Measured::Across(narrow)
    };
    (narrowest <= max_p2 && m[(2, 2)] <= max_y * max_y).then_some((m, measured))
}

impl Ekf {
    /// Fuses an absolute world pose whose time is `latency_s` before now, with covariance `r`
    /// of (x, y, yaw). The position is compared with the current one taken back along the
    /// velocity, as for the scan matcher's late revolutions.
    pub fn fuse_pose(&mut self, world: Pose2, r: Matrix3<f32>, latency_s: f32) -> Outcome {
        let (residual, h) = self.pose_residual(world, latency_s);
        self.update(residual, h, r)
    }

    /// [`Self::fuse_pose`] of the position along the unit world direction `across` and the
    /// heading only: the position perpendicular to `across` is left as it is.
    pub fn fuse_pose_across(
        &mut self,
        world: Pose2,
        r: Matrix3<f32>,
        across: Vec2,
        latency_s: f32,
    ) -> Outcome {
        let (residual, h) = self.pose_residual(world, latency_s);
        self.update_across(residual, h, r, across)
    }

    /// The update of a pose measurement (x, y, heading) with the position taken along the unit
    /// direction `across` only: rows `(acrossᵀ, 0)` and `(0, 0, 1)` of the residual, the model
    /// and the covariance (the marginal of the kept components). Nothing is said along the
    /// perpendicular, so its variance keeps growing with the prediction instead of being
    /// pinned by a value the measurement did not observe.
    pub(super) fn update_across(
        &mut self,
        residual: Vector3<f32>,
        h: SMatrix<f32, 3, N>,
        r: Matrix3<f32>,
        across: Vec2,
    ) -> Outcome {
        let keep = Matrix2x3::new(across.x, across.y, 0.0, 0.0, 0.0, 1.0);
        self.update(keep * residual, keep * h, keep * r * keep.transpose())
    }

    /// The residual of a world pose whose time is `latency_s` before now, and its model.
    fn pose_residual(&self, world: Pose2, latency_s: f32) -> (Vector3<f32>, SMatrix<f32, 3, N>) {
        let l = latency_s;
        let predicted = Vector3::new(
            self.x[ix::POS] - l * self.x[ix::VEL],
            self.x[ix::POS + 1] - l * self.x[ix::VEL + 1],
            self.x[ix::YAW],
        );
        let mut h = SMatrix::<f32, 3, N>::zeros();
        h[(0, ix::POS)] = 1.0;
        h[(1, ix::POS + 1)] = 1.0;
        h[(0, ix::VEL)] = -l;
        h[(1, ix::VEL + 1)] = -l;
        h[(2, ix::YAW)] = 1.0;
        let residual = Vector3::new(
            world.x - predicted.x,
            world.y - predicted.y,
            normalize_angle(world.theta - predicted.z),
        );
        (residual, h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::EkfConfig;

    fn fix(x: f32, y: f32, yaw: f32, reset_counter: u8) -> PoseFix {
        PoseFix {
            t_s: 0.0,
            position_m: [x, y],
            yaw_rad: yaw,
            covariance: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
            quality_pct: Some(80),
            reset_counter,
        }
    }

    fn fuse(frame: &mut CompanionFrame, ekf: &mut Ekf, f: &PoseFix) -> FixOutcome {
        frame.fuse(ekf, &PoseFixConfig::default(), f, 0.0)
    }

    #[test]
    fn the_first_fix_anchors_and_later_fixes_pull_the_estimate() {
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        // The companion's map is rotated a quarter turn and shifted from the world frame.
        let first = fix(2.0, 1.0, core::f32::consts::FRAC_PI_2, 0);
        assert_eq!(fuse(&mut frame, &mut ekf, &first), FixOutcome::Anchored);
        assert_eq!(ekf.state()[ix::POS], 0.0);
        let w = frame.to_world([2.0, 1.0]);
        assert!(w[0].abs() < 1e-6 && w[1].abs() < 1e-6, "{w:?}");
        assert!(frame.yaw_to_world(core::f32::consts::FRAC_PI_2).abs() < 1e-6);
        // Facing map +y is facing world +x: 0.05 m along map +y is 0.05 m along world +x.
        let moved = fix(2.0, 1.05, core::f32::consts::FRAC_PI_2, 0);
        assert_eq!(
            fuse(&mut frame, &mut ekf, &moved),
            FixOutcome::Fused(Outcome::Accepted)
        );
        let x = ekf.state();
        assert!(x[ix::POS] > 0.01 && x[ix::POS + 1].abs() < 1e-4, "{x}");
        assert_eq!(frame.counters().accepted, 1);
    }

    #[test]
    fn a_reset_counter_change_re_anchors_without_moving_the_estimate() {
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 7));
        let before = *ekf.state();
        // The companion re-localised: its pose jumped by 3 m. Same counter: a gross outlier.
        assert_eq!(
            fuse(&mut frame, &mut ekf, &fix(3.0, 0.0, 0.0, 7)),
            FixOutcome::Fused(Outcome::Rejected)
        );
        // With the counter bumped it is a new anchor, and the estimate stays where it was.
        assert_eq!(
            fuse(&mut frame, &mut ekf, &fix(3.0, 0.0, 0.0, 8)),
            FixOutcome::Anchored
        );
        assert_eq!(*ekf.state(), before);
        // Agreeing fixes after the jump are accepted and do not move the estimate.
        assert_eq!(
            fuse(&mut frame, &mut ekf, &fix(3.0, 0.0, 0.0, 8)),
            FixOutcome::Fused(Outcome::Accepted)
        );
        assert!((ekf.state()[ix::POS] - before[ix::POS]).abs() < 1e-6);
        assert_eq!(frame.counters().anchors, 2);
    }

    #[test]
    fn a_disagreeing_fix_without_a_reset_is_never_fused() {
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 0));
        for _ in 0..50 {
            let out = fuse(&mut frame, &mut ekf, &fix(5.0, 0.0, 0.0, 0));
            assert_eq!(out, FixOutcome::Fused(Outcome::Rejected));
        }
        assert_eq!(ekf.state()[ix::POS], 0.0);
        let c = frame.counters();
        assert_eq!((c.rejected, c.anchors), (50, 1));
    }

    #[test]
    fn bad_fixes_are_refused_counted_and_never_fused() {
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 0));
        let before = (*ekf.state(), *ekf.covariance());
        let good = fix(0.1, 0.0, 0.0, 0);
        let mut bad = [good; 9];
        bad[0].position_m[0] = f32::NAN;
        bad[1].covariance[0][0] = f32::NAN;
        bad[2].covariance[0][0] = 1e6; // absurdly unsure in every direction
        bad[2].covariance[1][1] = 1e6;
        bad[3].covariance[2][2] = -1e-4; // not a covariance
        bad[4].covariance[0][1] = 5e-4; // not symmetric
        bad[5].covariance = [[1e-4, 2e-4, 0.0], [2e-4, 1e-4, 0.0], [0.0, 0.0, 1e-4]]; // indefinite
        bad[6].yaw_rad = f32::INFINITY;
        bad[7].quality_pct = None; // lost
        bad[8].quality_pct = Some(5);
        for b in &bad {
            assert_eq!(fuse(&mut frame, &mut ekf, b), FixOutcome::Refused, "{b:?}");
        }
        let late = frame.fuse(&mut ekf, &PoseFixConfig::default(), &good, 2.0);
        assert_eq!(late, FixOutcome::Refused);
        let nan_age = frame.fuse(&mut ekf, &PoseFixConfig::default(), &good, f32::NAN);
        assert_eq!(nan_age, FixOutcome::Refused);
        let future = frame.fuse(&mut ekf, &PoseFixConfig::default(), &good, -1e6);
        assert_eq!(future, FixOutcome::Refused);
        assert_eq!((*ekf.state(), *ekf.covariance()), before);
        let c = frame.counters();
        assert_eq!((c.invalid, c.low_quality, c.late, c.accepted), (7, 2, 3, 0));
    }

    /// A fix known to 3 cm across the unit direction `along` and unobserved (10 m) along it,
    /// with the heading known to 0.01 rad: what a SLAM in a corridor sends.
    fn corridor_fix(x: f32, y: f32, along: Vec2) -> PoseFix {
        let (wide, narrow) = (100.0, 1.0e-3);
        let (u, v) = ([along.x, along.y], [-along.y, along.x]);
        let cov = |i: usize, j: usize| wide * u[i] * u[j] + narrow * v[i] * v[j];
        let mut f = fix(x, y, 0.0, 0);
        f.covariance = [
            [cov(0, 0), cov(0, 1), 0.0],
            [cov(1, 0), cov(1, 1), 0.0],
            [0.0, 0.0, 1e-4],
        ];
        f
    }

    #[test]
    fn a_fix_unobserved_along_a_corridor_corrects_only_across_it() {
        let along = Vec2::new(cosf(0.5), sinf(0.5));
        let across = along.perp();
        // The fix puts the vehicle 3 m down the corridor and 5 cm to the side.
        let off = along * 3.0 + across * 0.05;
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 0));
        let out = fuse(&mut frame, &mut ekf, &corridor_fix(off.x, off.y, along));
        assert_eq!(out, FixOutcome::Fused(Outcome::Accepted));
        let x = ekf.state();
        let moved = Vec2::new(x[ix::POS], x[ix::POS + 1]);
        // Across: pulled by P / (P + 4 R) = 0.0025 / 0.0065 of the 5 cm; along: not at all.
        let expected = 0.05 * 0.0025 / (0.0025 + 4.0 * 1e-3);
        assert!((moved.dot(across) - expected).abs() < 2e-4, "{moved:?}");
        assert!(moved.dot(along).abs() < 1e-5, "{moved:?}");
        // The variance along the corridor is left as it was; across it shrank.
        let p = ekf.covariance();
        let var = |u: Vec2| {
            let (a, b, c) = (
                p[(ix::POS, ix::POS)],
                p[(ix::POS, ix::POS + 1)],
                p[(ix::POS + 1, ix::POS + 1)],
            );
            u.x * u.x * a + 2.0 * u.x * u.y * b + u.y * u.y * c
        };
        assert!((var(along) - 0.0025).abs() < 1e-6, "{p}");
        assert!(var(across) < 0.0016, "{p}");
        assert_eq!(frame.counters().one_direction, 1);
        // The same fix believed in every direction is 3 m off: the gate refuses it.
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 0));
        let pinned = fuse(&mut frame, &mut ekf, &fix(off.x, off.y, 0.0, 0));
        assert_eq!(pinned, FixOutcome::Fused(Outcome::Rejected));
    }

    #[test]
    fn the_gate_weighs_a_corridor_fix_by_its_full_covariance() {
        // 0.5 m across a corridor known to 3 cm is far outside the gate, whatever along.
        let along = Vec2::new(0.0, 1.0);
        let mut ekf = Ekf::new(EkfConfig::default());
        let mut frame = CompanionFrame::default();
        fuse(&mut frame, &mut ekf, &fix(0.0, 0.0, 0.0, 0));
        let out = fuse(&mut frame, &mut ekf, &corridor_fix(0.5, 0.0, along));
        assert_eq!(out, FixOutcome::Fused(Outcome::Rejected));
        assert_eq!(ekf.state()[ix::POS], 0.0);
    }

    #[test]
    fn a_corridor_fix_is_well_formed_at_any_heading_of_the_corridor() {
        let c = PoseFixConfig::default();
        for k in 0..16 {
            let a = k as f32 * core::f32::consts::PI / 16.0;
            let along = Vec2::new(cosf(a), sinf(a));
            let f = corridor_fix(0.0, 0.0, along);
            let Some((_, Measured::Across(d))) = well_formed(&c, &f) else {
                panic!("{a}: {:?}", well_formed(&c, &f));
            };
            assert!(d.dot(along).abs() < 1e-3, "{a}: {d:?}");
        }
    }
}
