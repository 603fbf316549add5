//! Scan-match measurement: the matcher's pose change against the cloned reference pose.
//!
//! The prediction is the current (x, y, yaw) expressed in the frame of the clone:
//! `h = (R(-yaw_c) (p - p_c), yaw - yaw_c)`. A revolution is matched when it completes, but its
//! points were taken over the whole turn: the pose it gives is the pose of mid-revolution, a
//! latency L of half the revolution (0.1 s for the XV-11). Both the clone and the prediction
//! are taken back by L along the velocity, `p - L v`: at the 1 m/s of the swing after seed 000's
//! push, leaving this out put the estimate 0.1 m behind the vehicle, and the hold swung on that
//! lag for several seconds. When the matcher reports a degenerate axis (a
//! featureless corridor), only the translation across it and the rotation are used: the filter is
//! told nothing along the axis, so that direction's variance keeps growing with the IMU
//! prediction instead of being pinned by a made-up value.

use super::ekf::{ix, Ekf, Outcome, N};
use crate::geom::normalize_angle;
use crate::msgs::{ScanMatchDelta, ScanMatchStatus};
use libm::{cosf, sinf, sqrtf};
use nalgebra::{Matrix2x3, Matrix3, SMatrix, Vector2, Vector3};

impl Ekf {
    /// Fuses one scan-matcher result whose pose belongs `latency_s` before now. `ReferenceOnly`
    /// and `Failed` only move the reference when the matcher says so; a failed match is
    /// reported as `Invalid` so it is counted.
    pub fn fuse_scan_match(&mut self, m: &ScanMatchDelta, latency_s: f32) -> Outcome {
        let latency_s = if latency_s.is_finite() {
            latency_s.max(0.0)
        } else {
            0.0
        };
        let outcome = match m.status {
            ScanMatchStatus::Matched if self.has_reference => self.fuse_delta(m, latency_s),
            // A match against a reference this filter never saw cannot be used.
            ScanMatchStatus::Matched | ScanMatchStatus::Failed => Outcome::Invalid,
            ScanMatchStatus::ReferenceOnly => Outcome::Accepted,
        };
        if m.becomes_reference {
            self.clone_reference(latency_s);
        }
        outcome
    }

    fn fuse_delta(&mut self, m: &ScanMatchDelta, latency_s: f32) -> Outcome {
        let c = Matrix3::from_fn(|i, j| m.covariance[i][j]) * self.config.scan_covariance_scale;
        let z = Vector3::new(m.dx_m, m.dy_m, m.dtheta_rad);
        // The matcher's covariance is its information matrix inverted in f32; near a
        // degenerate geometry it can come out indefinite despite a positive diagonal. Fused,
        // such a noise lets the update take more variance out of a state than it had (in a gust
        // storm a velocity variance went from 0.004 to -0.08 in one match, and the estimate was
        // declared invalid mid-flight), so only a positive definite one is used.
        let well_formed = z.iter().all(|v| v.is_finite())
            && c.iter().all(|v| v.is_finite())
            && ((c + c.transpose()) * 0.5).cholesky().is_some();
        if !well_formed {
            return Outcome::Invalid;
        }
        let l = latency_s;
        let (px, py, yaw) = (
            self.x[ix::POS] - l * self.x[ix::VEL],
            self.x[ix::POS + 1] - l * self.x[ix::VEL + 1],
            self.x[ix::YAW],
        );
        let (cx, cy, cyaw) = (
            self.x[ix::CLONE],
            self.x[ix::CLONE + 1],
            self.x[ix::CLONE + 2],
        );
        let (s, co) = (sinf(cyaw), cosf(cyaw));
        let (dx, dy) = (px - cx, py - cy);
        // R(-yaw_c) (p - p_c) and its derivative with respect to yaw_c.
        let predicted = Vector2::new(co * dx + s * dy, -s * dx + co * dy);
        let d_dyaw_c = Vector2::new(-s * dx + co * dy, -co * dx - s * dy);
        let mut h = SMatrix::<f32, 3, N>::zeros();
        h[(0, ix::POS)] = co;
        h[(0, ix::POS + 1)] = s;
        h[(1, ix::POS)] = -s;
        h[(1, ix::POS + 1)] = co;
        h[(0, ix::VEL)] = -l * co;
        h[(0, ix::VEL + 1)] = -l * s;
        h[(1, ix::VEL)] = l * s;
        h[(1, ix::VEL + 1)] = -l * co;
        h[(0, ix::CLONE)] = -co;
        h[(0, ix::CLONE + 1)] = -s;
        h[(1, ix::CLONE)] = s;
        h[(1, ix::CLONE + 1)] = -co;
        h[(0, ix::CLONE + 2)] = d_dyaw_c.x;
        h[(1, ix::CLONE + 2)] = d_dyaw_c.y;
        h[(2, ix::YAW)] = 1.0;
        h[(2, ix::CLONE + 2)] = -1.0;
        let residual = Vector3::new(
            z.x - predicted.x,
            z.y - predicted.y,
            normalize_angle(z.z - normalize_angle(yaw - cyaw)),
        );

        match m.degenerate_axis {
            None => self.update(residual, h, c),
            Some([ax, ay]) => {
                let n = sqrtf(ax * ax + ay * ay);
                if !(n.is_finite() && n > 1e-3) {
                    return Outcome::Invalid;
                }
                // Keep the direction across the axis and the rotation: rows (n^T, 0), (0, 0, 1).
                let across = Matrix2x3::new(-ay / n, ax / n, 0.0, 0.0, 0.0, 1.0);
                self.update(
                    across * residual,
                    across * h,
                    across * c * across.transpose(),
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::EkfConfig;
    use crate::estimate::imu::tests::hover_step;

    fn matched(dx: f32, dy: f32, dth: f32, sigma: f32) -> ScanMatchDelta {
        ScanMatchDelta {
            t_s: 0.0,
            status: ScanMatchStatus::Matched,
            dx_m: dx,
            dy_m: dy,
            dtheta_rad: dth,
            covariance: [
                [sigma * sigma, 0.0, 0.0],
                [0.0, sigma * sigma, 0.0],
                [0.0, 0.0, 1e-4],
            ],
            degenerate_axis: None,
            becomes_reference: true,
        }
    }

    fn reference() -> ScanMatchDelta {
        ScanMatchDelta {
            status: ScanMatchStatus::ReferenceOnly,
            ..matched(0.0, 0.0, 0.0, 0.01)
        }
    }

    #[test]
    fn prediction_is_the_pose_seen_from_the_reference() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::YAW] = core::f32::consts::FRAC_PI_2;
        f.clone_reference(0.0);
        // Moved 0.1 m along world +y, i.e. straight ahead for a vehicle facing +y.
        f.x[ix::POS + 1] = 0.1;
        let m = ScanMatchDelta {
            becomes_reference: false,
            ..matched(0.1, 0.0, 0.0, 0.01)
        };
        let before = f.x;
        assert_eq!(f.fuse_scan_match(&m, 0.0), Outcome::Accepted);
        // The measurement agrees with the prediction: nothing moves.
        assert!((f.x - before).norm() < 1e-6);
    }

    #[test]
    fn a_match_without_a_reference_or_a_failure_is_counted_invalid() {
        let mut f = Ekf::new(EkfConfig::default());
        assert_eq!(
            f.fuse_scan_match(&matched(0.0, 0.0, 0.0, 0.01), 0.0),
            Outcome::Invalid
        );
        let failed = ScanMatchDelta {
            status: ScanMatchStatus::Failed,
            ..matched(0.0, 0.0, 0.0, 0.01)
        };
        assert_eq!(f.fuse_scan_match(&failed, 0.0), Outcome::Invalid);
        let nan = ScanMatchDelta {
            dx_m: f32::NAN,
            ..matched(0.0, 0.0, 0.0, 0.01)
        };
        assert_eq!(f.fuse_scan_match(&nan, 0.0), Outcome::Invalid);
        assert!(f.is_valid());
    }

    /// A noise with positive variances but a negative eigenvalue (a correlation of x and y
    /// above one) is no covariance: fused, it takes more variance out of the position than the
    /// filter holds.
    #[test]
    fn an_indefinite_match_covariance_is_refused_and_the_filter_stays_valid() {
        let mut f = Ekf::new(EkfConfig::default());
        f.fuse_scan_match(&reference(), 0.0);
        let before = f;
        let mut m = matched(0.01, 0.0, 0.0, 0.01);
        // Correlation 2: eigenvalues 3e-4 and -1e-4.
        m.covariance[0][1] = 2e-4;
        m.covariance[1][0] = 2e-4;
        assert_eq!(f.fuse_scan_match(&m, 0.0), Outcome::Invalid);
        assert_eq!(f, before);
        assert!(f.is_valid());
        // The same match with a correlation of 0.5 is used.
        m.covariance[0][1] = 0.5e-4;
        m.covariance[1][0] = 0.5e-4;
        assert_eq!(f.fuse_scan_match(&m, 0.0), Outcome::Accepted);
    }

    #[test]
    fn a_late_match_is_compared_with_the_pose_it_was_taken_at() {
        // Moving at 1 m/s along x, now at x = 1, the reference at the origin: a revolution
        // whose pose is 0.1 s old says 0.9.
        let moving = |latency_s: f32| {
            let mut f = Ekf::new(EkfConfig::default());
            f.x[ix::VEL] = 1.0;
            f.fuse_scan_match(&reference(), 0.0);
            for _ in 0..500 {
                f.predict(&hover_step(), 0.002).unwrap();
            }
            let out = f.fuse_scan_match(&matched(0.9, 0.0, 0.0, 0.01), latency_s);
            (out, f.x[ix::POS])
        };
        let (out, x) = moving(0.1);
        assert_eq!(out, Outcome::Accepted);
        assert!((x - 1.0).abs() < 1e-4, "{x}");
        let (out, x) = moving(0.0);
        assert_eq!(out, Outcome::Accepted);
        assert!(x < 0.95, "{x}");
    }

    #[test]
    fn the_reference_is_cloned_where_its_revolution_was_taken() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS] = 2.0;
        f.x[ix::VEL] = 1.0;
        f.p[(ix::POS, ix::VEL)] = 1e-3;
        f.p[(ix::VEL, ix::POS)] = 1e-3;
        f.clone_reference(0.1);
        assert!((f.x[ix::CLONE] - 1.9).abs() < 1e-6);
        // var(p - 0.1 v) = var p - 0.2 cov(p, v) + 0.01 var v.
        let (pp, vv) = (f.p[(ix::POS, ix::POS)], f.p[(ix::VEL, ix::VEL)]);
        let expected = pp - 0.2 * 1e-3 + 0.01 * vv;
        assert!((f.p[(ix::CLONE, ix::CLONE)] - expected).abs() < 1e-7);
        assert_eq!(f.p, f.p.transpose());
    }

    #[test]
    fn an_outlier_match_is_rejected() {
        let mut f = Ekf::new(EkfConfig::default());
        f.fuse_scan_match(&reference(), 0.0);
        for _ in 0..100 {
            f.predict(&hover_step(), 0.002).unwrap();
        }
        let before = f.x;
        let out = f.fuse_scan_match(
            &ScanMatchDelta {
                becomes_reference: false,
                ..matched(1.0, 0.0, 0.0, 0.01)
            },
            0.0,
        );
        assert_eq!(out, Outcome::Rejected);
        assert_eq!(f.x, before);
    }

    #[test]
    fn degenerate_axis_stays_unobserved_and_its_variance_grows() {
        let mut f = Ekf::new(EkfConfig::default());
        f.fuse_scan_match(&reference(), 0.0);
        // Matched against one keyframe, so across the corridor the position is pinned.
        let corridor = ScanMatchDelta {
            degenerate_axis: Some([1.0, 0.0]),
            becomes_reference: false,
            ..matched(0.0, 0.0, 0.0, 0.01)
        };
        let mut var_x = [0.0f32; 2];
        let mut var_y = [0.0f32; 2];
        for round in 0..2 {
            for _ in 0..50 {
                for _ in 0..100 {
                    f.predict(&hover_step(), 0.002).unwrap();
                }
                assert_eq!(f.fuse_scan_match(&corridor, 0.0), Outcome::Accepted);
            }
            var_x[round] = f.covariance()[(ix::POS, ix::POS)];
            var_y[round] = f.covariance()[(ix::POS + 1, ix::POS + 1)];
        }
        // Along the corridor: growing, and already far above the across-corridor variance.
        assert!(var_x[1] > var_x[0] * 1.2, "{var_x:?}");
        assert!(var_x[1] > 10.0 * var_y[1], "{var_x:?} {var_y:?}");
        // Across it the variance is bounded by the matches: it does not grow like x does.
        assert!(var_y[1] < var_y[0] * 1.2, "{var_y:?}");
    }
}
