//! The heading of the estimate frame, which nothing onboard measures.
//!
//! The frame is the vehicle's pose at power-up. The scan matcher measures the pose relative to
//! a cloned reference that lives in the same frame, so turning the whole frame about the
//! vertical (every position, velocity and heading, the clone's included) changes no match: the
//! frame's heading is what the initial yaw variance says and stays so. The filter's covariance
//! carries that turn as a direction in state space: the yaw with the positions and velocities
//! swung about the origin, `N(x) = (J p, J v, 1, J p_c, 1)` with `J` the quarter turn. A
//! correction that moves the estimate leaves the covariance's direction at the old estimate
//! while the next match's model, taken at the new one, is blind along the new one: the two
//! differ by `J` times the correction, and the match then informs, and moves, the frame's
//! heading (the filter inconsistency of EKF SLAM, Huang, Mourikis and Roumeliotis). Flying
//! away from its keyframes this turned the frame by a random walk: 0.02 rad over a 3 m square,
//! the flown path turned with it about the start.
//!
//! After every correction the covariance is therefore re-expressed about the corrected
//! estimate: with the heading's error taken as a turn of the whole frame (the invariant EKF's
//! error, Barrau and Bonnabel), position and velocity errors are those left once the frame's
//! turn is taken out, and the Jacobian from that error to the filter's own is
//! `T(x) = I + N_pv(x) e_yawᵀ + N_c(x) e_cloneyawᵀ`. The update ran with `T(x⁻)`; the
//! covariance is moved to `T(x⁺)` by `A = T(x⁺) T(x⁻)⁻¹ = I + J Δ_pv e_yawᵀ + J Δ_c e_cloneyawᵀ`,
//! `P ← A P Aᵀ`. The motion model's Jacobian already carries `N(x)` from one estimate to the
//! next (position and velocity move linearly, the yaw column holds what the specific force
//! added, [`super::imu`]), and the match's model at any estimate is blind along `N` there
//! ([`super::scan_match`]): together, no relative match informs the frame's heading.
//! Absolute measurements (a companion's map pose) do, as they should.

use super::ekf::{ix, symmetrise, Ekf, State, N};

impl Ekf {
    /// Moves the covariance's frame-turn direction from the estimate `before` a correction to
    /// the current one (see the module documentation). The tilt error is left out: the
    /// estimator hands it to the tilt filter and zeroes it after every correction, so its part
    /// of the turn is nil whenever the covariance is propagated.
    pub(super) fn follow_frame_turn(&mut self, before: &State) {
        let d = self.x - before;
        // J times the change of each horizontal pair, in the rows of that pair.
        let turned = |bases: &[usize]| {
            let mut shift = State::zeros();
            for &base in bases {
                shift[base] = -d[base + 1];
                shift[base + 1] = d[base];
            }
            shift
        };
        let (live, clone) = (turned(&[ix::POS, ix::VEL]), turned(&[ix::CLONE]));
        if live.iter().chain(clone.iter()).all(|&v| v == 0.0) {
            return;
        }
        let (yaw, clone_yaw) = (ix::YAW, ix::CLONE + 2);
        // B = A P, then A P Aᵀ = B Aᵀ, worked in place: every N x N temporary is 1.3 KB of a
        // microcontroller's stack.
        let p = &mut self.p;
        let (row, clone_row) = (p.row(yaw).transpose(), p.row(clone_yaw).transpose());
        for i in 0..N {
            for j in 0..N {
                p[(i, j)] += live[i] * row[j] + clone[i] * clone_row[j];
            }
        }
        let (column, clone_column) = (p.column(yaw).into_owned(), p.column(clone_yaw).into_owned());
        for i in 0..N {
            for j in 0..N {
                p[(i, j)] += column[i] * live[j] + clone_column[i] * clone[j];
            }
        }
        symmetrise(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::attitude::Tilt;
    use crate::estimate::ekf::{EkfConfig, Outcome, N};
    use crate::estimate::imu::tests::hover_step;
    use crate::estimate::imu::ImuStep;
    use crate::msgs::{ScanMatchDelta, ScanMatchStatus, GRAVITY_M_S2};
    use nalgebra::SVector;

    /// A match of the pose (dx, dy) seen from the reference, heading unchanged, 2 cm and 0.01
    /// rad one-sigma (before the filter's covariance scale).
    fn matched(dx: f32, dy: f32, becomes_reference: bool) -> ScanMatchDelta {
        ScanMatchDelta {
            t_s: 0.0,
            status: ScanMatchStatus::Matched,
            dx_m: dx,
            dy_m: dy,
            dtheta_rad: 0.0,
            covariance: [[4e-4, 0.0, 0.0], [0.0, 4e-4, 0.0], [0.0, 0.0, 1e-4]],
            degenerate_axis: None,
            becomes_reference,
        }
    }

    /// From rest at the origin, heading 0, accelerates along +x at 1 m/s^2 for a second and
    /// flies on, matching every 0.1 s against a keyframe renewed every 10 matches. The
    /// accelerometer reads 0.2 m/s^2 sideways that the filter does not know of, and the matches'
    /// sideways readings alternate +-2 cm about the truth (0): every match corrects the
    /// position and velocity the filter predicted.
    fn fly_away(config: EkfConfig, matches: usize) -> Ekf {
        const ACCEL: f32 = 1.0;
        let mut f = Ekf::new(config);
        let start = ScanMatchDelta {
            status: ScanMatchStatus::ReferenceOnly,
            ..matched(0.0, 0.0, true)
        };
        f.fuse_scan_match(&start, 0.0);
        let accelerating = ImuStep {
            accel_m_s2: [0.0, 0.2, libm::hypotf(GRAVITY_M_S2, ACCEL)],
            tilt: Tilt::from_angles(0.0, libm::atanf(ACCEL / GRAVITY_M_S2)),
            ..hover_step()
        };
        let cruising = ImuStep {
            accel_m_s2: [0.0, 0.2, GRAVITY_M_S2],
            ..hover_step()
        };
        let truth = |t: f32| {
            let t_accel = t.min(1.0);
            0.5 * ACCEL * t_accel * t_accel + ACCEL * (t - t_accel)
        };
        let mut keyframe_x = 0.0;
        for k in 1..=matches {
            let t = k as f32 * 0.1;
            let step = if t <= 1.0 { accelerating } else { cruising };
            for _ in 0..50 {
                f.predict(&step, 0.002).unwrap();
            }
            let side = if k % 3 == 0 { -0.02 } else { 0.02 };
            let renew = k % 10 == 0;
            let m = matched(truth(t) - keyframe_x, side, renew);
            assert_eq!(f.fuse_scan_match(&m, 0.0), Outcome::Accepted, "match {k}");
            if renew {
                keyframe_x = truth(t);
            }
        }
        f
    }

    #[test]
    fn relative_matches_leave_the_frame_heading_as_uncertain_as_it_started() {
        // Given an uncertain frame heading and no gyro noise, nothing adds to the heading's
        // variance and relative matches may take none out: the yaw's one-sigma stays the
        // initial 0.05 rad. With the covariance left at the estimates before each correction
        // the matches informed the frame: 0.04993 after 60.
        let config = EkfConfig {
            initial_std: [0.05, 0.05, 0.05],
            initial_bias_std: [0.3, 0.0],
            gyro_noise_density: 0.0,
            gyro_bias_walk: 0.0,
            ..EkfConfig::default()
        };
        let f = fly_away(config, 60);
        let sigma = libm::sqrtf(f.p[(ix::YAW, ix::YAW)]);
        assert!((sigma - 0.05).abs() < 1e-5, "{sigma}");
    }

    /// The frame-turn direction at the estimate `x`: positions and velocities swung about the
    /// origin, headings turned.
    fn frame_turn(x: &State) -> SVector<f32, N> {
        let mut n = SVector::<f32, N>::zeros();
        for base in [ix::POS, ix::VEL, ix::CLONE] {
            n[base] = -x[base + 1];
            n[base + 1] = x[base];
        }
        n[ix::YAW] = 1.0;
        n[ix::CLONE + 2] = 1.0;
        n
    }

    #[test]
    fn a_correction_carries_the_frame_turn_to_the_corrected_estimate() {
        // A covariance that is all frame turn (0.05 rad of it) at one estimate is, once the
        // estimate is corrected, all frame turn at the corrected one.
        let mut f = Ekf::new(EkfConfig::default());
        for (i, v) in [
            (ix::POS, 2.0),
            (ix::POS + 1, -1.0),
            (ix::VEL, 0.5),
            (ix::CLONE, 1.5),
        ] {
            f.x[i] = v;
        }
        let before = f.x;
        let n = frame_turn(&before);
        f.p = n * n.transpose() * 0.0025;
        for (i, v) in [(ix::POS, 0.03), (ix::POS + 1, 0.02), (ix::VEL + 1, -0.1)] {
            f.x[i] += v;
        }
        f.x[ix::CLONE + 1] += 0.01;
        f.follow_frame_turn(&before);
        let moved = frame_turn(&f.x);
        let expected = moved * moved.transpose() * 0.0025;
        assert!((f.p - expected).abs().max() < 1e-7, "{}", f.p - expected);
        assert_eq!(f.p, f.p.transpose());
    }
}
