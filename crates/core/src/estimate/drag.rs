//! Drag measurement: a multirotor's accelerometer reads its air-relative velocity in the body
//! x/y specific force.
//!
//! Thrust acts along body z, so in the body x/y plane the only force the accelerometer feels is
//! aerodynamic: rotor induced drag (blade flapping) and fuselage drag, close to linear in the
//! air-relative velocity at indoor speeds, `f_xy = -c (R^T v)_xy + b_xy` (Leishman, Martin and
//! Salaün 2010, "The true role of accelerometer feedback in quadrotor control"; the "drag
//! fusion" of PX4's and ArduPilot's EKFs). It is what keeps an IMU-only velocity bounded: the
//! tilt-and-thrust prediction integrates any tilt error into a growing velocity, while this
//! measurement ties the velocity to the force the vehicle feels. Air is taken as still: a
//! draught reads as ground velocity, which the measurement noise allows for (two wind states make
//! no measurable difference in the simulator's draughty room, see BENCHMARKS.md).
//!
//! The accelerometer is averaged over a window before it is fused, which divides its noise and
//! keeps the filter update off the per-sample path. Only fused while the vehicle flies on its
//! rotors: on the floor the x/y specific force is gravity along a tilted floor, and a push or a
//! collision is a force this model does not know (the innovation gate rejects it).

use super::attitude::Tilt;
use super::ekf::{ix, Ekf, Outcome, N};
use super::imu::rotation;
use crate::matching::linalg::sym2_eigen;
use nalgebra::{Matrix2, Matrix3, SMatrix, Vector2, Vector3};

/// Drag model settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragConfig {
    /// Linear drag per unit mass c (1/s): body x/y specific force per m/s of body air velocity.
    /// Default: the simulator's F450, 0.12 N/(m/s) on 1.2 kg. A real airframe's figure comes from
    /// a flight with the lidar working (specific force against the lidar velocity); zero turns
    /// the measurement off.
    pub drag_per_s: f32,
    /// Accelerometer samples are averaged over this long before one fusion (s).
    pub window_s: f32,
    /// One-sigma of a window's mean x/y specific force about the model (m/s^2). Accelerometer
    /// noise over the window (0.02 m/s^2/sqrt(Hz) / sqrt(0.1 s) = 0.06), draughts (0.3 m/s of
    /// air at c = 0.1 is 0.03, lasting seconds) and the quadratic drag the model leaves out
    /// (0.01 at 0.3 m/s) come to about 0.1; it is widened to 0.3 because at 0.1 the IMU-only
    /// velocity after a lidar loss follows the accelerometer's noise, the hold chases it, and
    /// the vehicle strays further (BENCHMARKS.md, closed-loop flight).
    pub specific_force_std_m_s2: f32,
    /// One-sigma of the window's mean along a horizontal direction whose velocity the lidar
    /// does not observe (m/s^2): the figure the widened `specific_force_std_m_s2` is made of,
    /// unwidened. Down a featureless corridor the scan match says nothing of the speed along
    /// it, and the drag reading is the only thing that bounds it; at the widened figure the
    /// speed's one-sigma grows about 0.1 m/s a second there and the estimate is lost within
    /// seconds of a blank stretch of wall, while holding on a noisy drag speed along one axis
    /// is the lesser harm. Along the observed direction the widened figure stays, so a hold
    /// and a flight the lidar sees are unchanged.
    pub unobserved_specific_force_std_m_s2: f32,
    /// A horizontal direction counts as unobserved while the filter's velocity one-sigma
    /// along it exceeds this (m/s). With the lidar matching, the velocity is known to a few
    /// cm/s on every axis; a blank corridor passes 0.1 m/s about a second into the blank.
    pub unobserved_velocity_std_m_s: f32,
    /// ... and exceeds this many times the one-sigma across it: a direction is unobserved
    /// when the lidar sees the other one, not when the match is merely noisy on both (a hold
    /// with a slow lidar).
    pub unobserved_std_ratio: f32,
    /// Normalised innovation squared above which a window is rejected. Tighter than the
    /// EKF's general gate: a window that overlaps a push or a bump carries a force this model
    /// does not know, and at the general gate the edges of seed 000's push passed and bent the
    /// accelerometer bias.
    pub gate_nis: f32,
    /// Keep fusing after the lidar is lost. In still air that bounds the IMU-only velocity
    /// (simulated, mean stray 6 s after the loss 0.44 m against 0.60 m without), but a draught
    /// reads as ground velocity, and in the simulated room's draughts (0.3 m/s) the stray was
    /// larger over the seconds a lidar-lost failsafe flies (0.74 against 0.65 m at 6 s, 0.23
    /// against 0.20 m at touchdown). Off by default: the drag reading then serves to tell the
    /// accelerometer bias from tilt while the lidar works, which halves the worst tilt error
    /// at the moment of a loss.
    pub without_lidar: bool,
}

impl Default for DragConfig {
    fn default() -> Self {
        Self {
            drag_per_s: 0.1,
            window_s: 0.1,
            specific_force_std_m_s2: 0.3,
            unobserved_specific_force_std_m_s2: 0.1,
            unobserved_velocity_std_m_s: 0.15,
            unobserved_std_ratio: 2.0,
            // Chi-square 99 % for two dimensions.
            gate_nis: 9.21,
            without_lidar: false,
        }
    }
}

/// The accelerometer's x/y specific force summed over the current window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DragWindow {
    sum_m_s2: [f32; 2],
    samples: u32,
    span_s: f32,
}

impl DragWindow {
    pub fn add(&mut self, accel_m_s2: [f32; 3], dt: f32) {
        self.sum_m_s2[0] += accel_m_s2[0];
        self.sum_m_s2[1] += accel_m_s2[1];
        self.samples += 1;
        self.span_s += dt;
    }

    /// The window's mean once it spans `window_s`, and a fresh window; `None` before that.
    pub fn take(&mut self, window_s: f32) -> Option<[f32; 2]> {
        if self.span_s < window_s || self.samples == 0 {
            return None;
        }
        let n = self.samples as f32;
        let mean = [self.sum_m_s2[0] / n, self.sum_m_s2[1] / n];
        *self = Self::default();
        Some(mean)
    }

    /// Forgets the samples so far (the vehicle touched the floor, or was not flying).
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}

impl Ekf {
    /// Fuses one window's mean body x/y specific force, taken at the given tilt.
    pub fn fuse_drag(&mut self, c: &DragConfig, specific_m_s2: [f32; 2], tilt: &Tilt) -> Outcome {
        let finite = [tilt.sin_roll, tilt.cos_roll, tilt.sin_pitch, tilt.cos_pitch]
            .iter()
            .all(|v| v.is_finite());
        if !(c.drag_per_s > 0.0 && finite) {
            return Outcome::Invalid;
        }
        let k = c.drag_per_s;
        let yaw = self.x[ix::YAW];
        let (s, co) = libm::sincosf(yaw);
        let r = rotation(tilt, (s, co));
        let rt = r.transpose();
        let v = self.x.fixed_rows::<3>(ix::VEL).into_owned();
        let body = rt * v;
        let bias = Vector2::new(self.x[ix::ACCEL_BIAS], self.x[ix::ACCEL_BIAS + 1]);
        let predicted = Vector2::new(-k * body.x, -k * body.y) + bias;
        let residual = Vector2::from(specific_m_s2) - predicted;

        let mut h = SMatrix::<f32, 2, N>::zeros();
        // d(R^T v)/d(v) = R^T.
        for i in 0..2 {
            for j in 0..3 {
                h[(i, ix::VEL + j)] = -k * rt[(i, j)];
            }
            h[(i, ix::ACCEL_BIAS + i)] = 1.0;
        }
        // R = Rz(yaw) T with T the tilt, so d(R^T v)/d(yaw) = T^T d(Rz^T)/d(yaw) v.
        let tilt_t = rotation(tilt, (0.0, 1.0)).transpose();
        let d_yaw = tilt_t * Vector3::new(-s * v.x + co * v.y, -co * v.x - s * v.y, 0.0);
        // True R = exp(phi) R: R^T v becomes R^T (v + v x phi), so d/d(phi) = R^T [v]x.
        let d_tilt = rt * Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0);
        for i in 0..2 {
            h[(i, ix::YAW)] = -k * d_yaw[i];
            h[(i, ix::TILT)] = -k * d_tilt[(i, 0)];
            h[(i, ix::TILT + 1)] = -k * d_tilt[(i, 1)];
        }
        let r = self.drag_noise(c, &rt);
        let position = [
            ix::POS,
            ix::POS + 1,
            ix::POS + 2,
            ix::CLONE,
            ix::CLONE + 1,
            ix::CLONE + 2,
        ];
        self.update_considering(residual, h, r, &position, c.gate_nis)
    }

    /// The measurement covariance in body x/y: `specific_force_std_m_s2` on both axes, except
    /// along the horizontal direction of the largest velocity variance while its one-sigma
    /// exceeds `unobserved_velocity_std_m_s`, which gets `unobserved_specific_force_std_m_s2`.
    /// `rt` turns world vectors into the body frame.
    fn drag_noise(&self, c: &DragConfig, rt: &Matrix3<f32>) -> Matrix2<f32> {
        let wide = c.specific_force_std_m_s2 * c.specific_force_std_m_s2;
        let r = Matrix2::identity() * wide;
        let (vx, vy) = (ix::VEL, ix::VEL + 1);
        let p = &self.p;
        let (largest, smallest, smallest_axis) = sym2_eigen(p[(vx, vx)], p[(vx, vy)], p[(vy, vy)]);
        let threshold = c.unobserved_velocity_std_m_s;
        let ratio = c.unobserved_std_ratio;
        if !(largest > threshold * threshold && largest > ratio * ratio * smallest) {
            return r;
        }
        // The direction of the largest variance, in the body x/y plane (the tilt shortens it).
        let weak = rt * Vector3::new(-smallest_axis.y, smallest_axis.x, 0.0);
        let b = Vector2::new(weak.x, weak.y);
        let norm = b.norm();
        if !norm.is_finite() || norm <= 0.5 {
            return r;
        }
        let b = b / norm;
        let tight = c.unobserved_specific_force_std_m_s2 * c.unobserved_specific_force_std_m_s2;
        r - b * b.transpose() * (wide - tight)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ekf::EkfConfig;
    use crate::estimate::imu::tests::hover_step;
    use crate::estimate::imu::ImuStep;
    use crate::msgs::GRAVITY_M_S2;

    #[test]
    fn window_mean_comes_out_once_the_window_is_full() {
        let mut w = DragWindow::default();
        w.add([0.1, -0.2, 9.8], 0.05);
        assert_eq!(w.take(0.1), None);
        w.add([0.3, 0.0, 9.8], 0.05);
        let mean = w.take(0.1).unwrap();
        assert!((mean[0] - 0.2).abs() < 1e-6 && (mean[1] + 0.1).abs() < 1e-6);
        assert_eq!(w, DragWindow::default());
    }

    /// A vehicle pitched 2 degrees forward that the filter starts out believing level, with
    /// the EKF's tilt estimate fed back as the estimator does. Returns the final velocity error
    /// (m/s) and tilt error (rad). Without drag the tilt is unobservable and the IMU-only
    /// velocity runs away at g tan(2 degrees); with it, the filter finds the tilt and bounds the
    /// velocity error.
    fn run(drag: bool) -> (f32, f32) {
        let mut f = Ekf::new(EkfConfig::default());
        let c = DragConfig::default();
        let tilt = 2.0f32.to_radians();
        let (dt, mut v_true, mut pitch_est) = (0.002f32, 0.0f32, 0.0f32);
        let mut window = DragWindow::default();
        for _ in 0..(20.0 / dt) as usize {
            // True dynamics along x: thrust tilted forward, drag -c v.
            let drag_accel = -c.drag_per_s * v_true;
            v_true += (GRAVITY_M_S2 * libm::tanf(tilt) + drag_accel) * dt;
            // The accelerometer: thrust on body z (holding height), drag on body x.
            let specific = [drag_accel, 0.0, GRAVITY_M_S2 / libm::cosf(tilt)];
            let step = ImuStep {
                accel_m_s2: specific,
                tilt: Tilt::from_angles(0.0, pitch_est),
                ..hover_step()
            };
            f.predict(&step, dt).unwrap();
            window.add(specific, dt);
            if let Some(mean) = window.take(c.window_s) {
                if drag {
                    f.fuse_drag(&c, mean, &Tilt::from_angles(0.0, pitch_est));
                }
                // About world y at zero heading is pitch.
                pitch_est += f.take_tilt_error().0[1];
            }
        }
        (
            (f.state()[ix::VEL] - v_true).abs(),
            (pitch_est - tilt).abs(),
        )
    }

    #[test]
    fn drag_bounds_the_velocity_error_a_tilt_error_builds() {
        let (v_with, tilt_with) = run(true);
        let (v_without, tilt_without) = run(false);
        assert!(v_without > 1.0, "without drag {v_without}");
        assert_eq!(tilt_without, 2.0f32.to_radians());
        // Hovering, a tilt error and an accelerometer bias that cancel it look alike; what is
        // left of the tilt is taken up by the bias, and the velocity by both (0.42 m/s after
        // 20 s, against 6.8 without drag).
        assert!(
            v_with < 0.6 && v_with < v_without / 5.0,
            "with drag {v_with}"
        );
        assert!(tilt_with < 0.3f32.to_radians(), "with drag {tilt_with}");
    }

    #[test]
    fn a_push_is_rejected_and_a_breeze_is_not() {
        let settled = || {
            let mut f = Ekf::new(EkfConfig::default());
            f.reset_variance(&[(ix::ACCEL_BIAS, 1e-4), (ix::ACCEL_BIAS + 1, 1e-4)]);
            f
        };
        let c = DragConfig::default();
        // Seed 000's 2 N on 1.2 kg is 1.7 m/s^2 (the EKF's general gate would let it through).
        let mut pushed = settled();
        let before = pushed;
        assert_eq!(
            pushed.fuse_drag(&c, [1.7, 0.0], &Tilt::LEVEL),
            Outcome::Rejected
        );
        assert_eq!(pushed, before);
        // 1 m/s of air against the vehicle: 0.1 m/s^2.
        let mut breeze = settled();
        assert_eq!(
            breeze.fuse_drag(&c, [-0.1, 0.0], &Tilt::LEVEL),
            Outcome::Accepted
        );
        assert!(breeze.state()[ix::VEL] > 0.0);
    }

    #[test]
    fn the_noise_is_unwidened_only_along_an_unobserved_direction() {
        let c = DragConfig::default();
        let (wide, tight) = (0.3f32 * 0.3, 0.1f32 * 0.1);
        // Heading +y (body x is world y), level; velocity variance `along` on world y, `across`
        // on world x.
        let noise = |along: f32, across: f32| {
            let mut f = Ekf::new(EkfConfig::default());
            f.x[ix::YAW] = core::f32::consts::FRAC_PI_2;
            f.p[(ix::VEL, ix::VEL)] = across;
            f.p[(ix::VEL + 1, ix::VEL + 1)] = along;
            let rt = rotation(&Tilt::LEVEL, libm::sincosf(f.x[ix::YAW])).transpose();
            f.drag_noise(&c, &rt)
        };
        let close = |a: Matrix2<f32>, b: Matrix2<f32>| (a - b).abs().max() < 1e-6;
        // A corridor along world y: unwidened on body x only.
        assert!(close(
            noise(0.25, 0.01),
            Matrix2::new(tight, 0.0, 0.0, wide)
        ));
        // Known on both axes, or unknown on both (a slow lidar): widened on both.
        assert!(close(noise(0.01, 0.01), Matrix2::identity() * wide));
        assert!(close(noise(0.25, 0.2), Matrix2::identity() * wide));
    }

    #[test]
    fn no_drag_coefficient_means_no_measurement() {
        let mut f = Ekf::new(EkfConfig::default());
        let c = DragConfig {
            drag_per_s: 0.0,
            ..DragConfig::default()
        };
        let before = f;
        assert_eq!(f.fuse_drag(&c, [0.1, 0.0], &Tilt::LEVEL), Outcome::Invalid);
        assert_eq!(f, before);
    }
}
