//! IMU prediction: the accelerometer and gyro drive the EKF's motion model.
//!
//! Specific force, bias-corrected and rotated to the world with the tilt filter's roll and pitch
//! and the EKF's yaw, plus gravity, is the acceleration; yaw advances with the Euler-rate form of
//! the body rates. Process noise is white accelerometer and gyro noise plus bias random walks.

use super::attitude::Tilt;
use super::ekf::{all_finite, ix, Ekf, N};
use crate::geom::normalize_angle;
use crate::msgs::GRAVITY_M_S2;
use nalgebra::{Matrix3, Vector3};

/// What the prediction needs besides the raw sample: the tilt (from the attitude filter) and the
/// gyro x/y rates with their bias removed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuStep {
    pub accel_m_s2: [f32; 3],
    /// Body rates, x and y bias-corrected by the tilt filter; z raw (the EKF owns its bias).
    pub gyro_rad_s: [f32; 3],
    pub tilt: Tilt,
}

/// Why a prediction was skipped (the state is unchanged).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PredictError {
    NonFinite,
    BadDt,
}

/// ZYX Euler rotation, body FLU to world, from the tilt and the heading's (sine, cosine).
pub(super) fn rotation(tilt: &Tilt, (sy, cy): (f32, f32)) -> Matrix3<f32> {
    let (sr, cr) = (tilt.sin_roll, tilt.cos_roll);
    let (sp, cp) = (tilt.sin_pitch, tilt.cos_pitch);
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

impl Ekf {
    /// Advances the state by `dt` with one IMU sample; the covariance catches up every
    /// `covariance_period_s` using the Jacobian at the current state.
    pub fn predict(&mut self, imu: &ImuStep, dt: f32) -> Result<(), PredictError> {
        // A NaN fails both comparisons.
        if !(dt > 0.0 && dt < 1.0) {
            return Err(PredictError::BadDt);
        }
        let t = &imu.tilt;
        let finite = all_finite(&imu.accel_m_s2)
            && all_finite(&imu.gyro_rad_s)
            && all_finite(&[t.sin_roll, t.cos_roll, t.sin_pitch, t.cos_pitch]);
        if !finite {
            return Err(PredictError::NonFinite);
        }
        let yaw = self.x[ix::YAW];
        let r = rotation(&imu.tilt, libm::sincosf(yaw));
        let bias = self.x.fixed_rows::<3>(ix::ACCEL_BIAS).into_owned();
        let specific = Vector3::from(imu.accel_m_s2) - bias;
        let world_specific = r * specific;
        let accel = world_specific - Vector3::new(0.0, 0.0, GRAVITY_M_S2);
        let v = self.x.fixed_rows::<3>(ix::VEL).into_owned();
        let (sr, cr) = (imu.tilt.sin_roll, imu.tilt.cos_roll);
        let cp = imu.tilt.cos_pitch.max(0.1);
        let rate_z = imu.gyro_rad_s[2] - self.x[ix::GYRO_Z_BIAS];
        let yaw_rate = (sr * imu.gyro_rad_s[1] + cr * rate_z) / cp;

        let mut pos = self.x.fixed_rows_mut::<3>(ix::POS);
        pos += v * dt + accel * (0.5 * dt * dt);
        let mut vel = self.x.fixed_rows_mut::<3>(ix::VEL);
        vel += accel * dt;
        self.x[ix::YAW] = normalize_angle(yaw + yaw_rate * dt);

        let pending = &mut self.pending;
        for i in 0..2 {
            pending.position[i] += pending.velocity[i] * dt + accel[i] * (0.5 * dt * dt);
            pending.velocity[i] += accel[i] * dt;
        }
        pending.dt += dt;
        if pending.dt >= self.config.covariance_period_s {
            let moved = core::mem::take(&mut self.pending);
            self.propagate_covariance(&r, &world_specific, cr / cp, &moved);
        }
        Ok(())
    }

    /// `P = F P F^T + Q` over the pending motion, with F the motion model's Jacobian.
    /// `yaw_gain` is d(yaw rate)/d(gyro z) = cos(roll)/cos(pitch).
    fn propagate_covariance(
        &mut self,
        r: &Matrix3<f32>,
        world_specific: &Vector3<f32>,
        yaw_gain: f32,
        moved: &PendingMotion,
    ) {
        let dt = moved.dt;
        // F = I + G with G's 23 entries out of 324, all in the rows of the MOVED states.
        // B = P F^T differs from P only in the moved columns, and F P F^T = F B differs from B
        // only in the moved rows, which by symmetry are B's moved columns except where a moved
        // row meets a moved column. So: the moved columns of B (column operations, over
        // contiguous memory), then the 9 x 9 block where moved meets moved. Dense products
        // would be the largest single cost of the closed loop, row operations on P the next.
        let g = jacobian_entries(r, world_specific, yaw_gain, moved);
        // Column k of the column-major matrix.
        let column = |k: usize| k * N..(k + 1) * N;
        let p = self.p.as_slice();
        let mut b = [[0.0f32; N]; MOVED.len()];
        for (col, &k) in b.iter_mut().zip(&MOVED) {
            col.copy_from_slice(&p[column(k)]);
        }
        for &(i, j, v) in &g {
            for (out, x) in b[SLOT[i]].iter_mut().zip(&p[column(j)]) {
                *out += v * x;
            }
        }
        let mut block: [[f32; MOVED.len()]; MOVED.len()] =
            core::array::from_fn(|m| core::array::from_fn(|n| b[n][MOVED[m]]));
        for &(i, j, v) in &g {
            for (out, col) in block[SLOT[i]].iter_mut().zip(&b) {
                *out += v * col[j];
            }
        }
        let p = self.p.as_mut_slice();
        for (col, &k) in b.iter().zip(&MOVED) {
            p[column(k)].copy_from_slice(col);
            for (row, &x) in col.iter().enumerate() {
                p[row * N + k] = x;
            }
        }
        // One triangle of the block, mirrored: P stays exactly symmetric.
        for (m, (row, &i)) in block.iter().zip(&MOVED).enumerate() {
            for (&x, &k) in row[..=m].iter().zip(&MOVED) {
                p[k * N + i] = x;
                p[i * N + k] = x;
            }
        }

        let c = &self.config;
        let qa = c.accel_noise_density * c.accel_noise_density * dt;
        let qg = c.gyro_noise_density * c.gyro_noise_density * dt;
        let qba = c.accel_bias_walk * c.accel_bias_walk * dt;
        let qbg = c.gyro_bias_walk * c.gyro_bias_walk * dt;
        for i in 0..3 {
            // White acceleration: velocity grows by qa, position by qa dt^2 / 3 (correlated).
            self.p[(ix::VEL + i, ix::VEL + i)] += qa;
            self.p[(ix::POS + i, ix::POS + i)] += qa * dt * dt / 3.0;
            self.p[(ix::POS + i, ix::VEL + i)] += qa * dt / 2.0;
            self.p[(ix::VEL + i, ix::POS + i)] += qa * dt / 2.0;
            self.p[(ix::ACCEL_BIAS + i, ix::ACCEL_BIAS + i)] += qba;
        }
        self.p[(ix::YAW, ix::YAW)] += qg;
        self.p[(ix::TILT, ix::TILT)] += qg;
        self.p[(ix::TILT + 1, ix::TILT + 1)] += qg;
        self.p[(ix::GYRO_Z_BIAS, ix::GYRO_Z_BIAS)] += qbg;
        self.p[(ix::GYRO_XY_BIAS, ix::GYRO_XY_BIAS)] += qbg;
        self.p[(ix::GYRO_XY_BIAS + 1, ix::GYRO_XY_BIAS + 1)] += qbg;
    }
}

/// The states the motion model's Jacobian moves off the identity: its entries' rows.
const MOVED: [usize; 9] = [
    ix::POS,
    ix::POS + 1,
    ix::POS + 2,
    ix::VEL,
    ix::VEL + 1,
    ix::VEL + 2,
    ix::YAW,
    ix::TILT,
    ix::TILT + 1,
];

/// Where each moved state sits in [`MOVED`] (0 for the others, which no Jacobian entry has
/// as its row: `sparse_propagation_equals_the_dense_product` would fail if one did).
const SLOT: [usize; N] = {
    let mut slots = [0; N];
    let mut m = 0;
    while m < MOVED.len() {
        slots[MOVED[m]] = m;
        m += 1;
    }
    slots
};

/// The motion since the covariance last caught up with the state: its duration (s), and the
/// horizontal velocity (m/s) and position (m) the specific force added over it, the position's
/// beyond what the velocity at its start carried.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct PendingMotion {
    pub dt: f32,
    pub velocity: [f32; 2],
    pub position: [f32; 2],
}

/// Number of off-identity entries of the motion model's Jacobian.
const JACOBIAN_ENTRIES: usize = 25;

/// The motion model's Jacobian minus the identity, as (row, column, value), over the pending
/// motion; the tilt and bias columns with the latest sample's rotation and specific force.
fn jacobian_entries(
    r: &Matrix3<f32>,
    world_specific: &Vector3<f32>,
    yaw_gain: f32,
    moved: &PendingMotion,
) -> [(usize, usize, f32); JACOBIAN_ENTRIES] {
    let (u, dt) = (world_specific, moved.dt);
    let mut g = [(0, 0, 0.0); JACOBIAN_ENTRIES];
    let mut k = 0;
    let mut put = |i: usize, j: usize, v: f32| {
        g[k] = (i, j, v);
        k += 1;
    };
    for i in 0..3 {
        put(ix::POS + i, ix::VEL + i, dt);
    }
    // d(R f)/d(yaw) = (-(R f)_y, (R f)_x, 0), integrated over the period from every sample,
    // not the last one times the period: a turn of the heading turns exactly the velocity and
    // position the specific force added, so the covariance carries the whole frame's turn from
    // one estimate to the next (super::frame). With the last sample's force the two parted by
    // the accelerometer's noise every period, a random walk of what the covariance took for
    // the frame's turn.
    let [dv, dp] = [moved.velocity, moved.position];
    put(ix::VEL, ix::YAW, -dv[1]);
    put(ix::VEL + 1, ix::YAW, dv[0]);
    put(ix::POS, ix::YAW, -dp[1]);
    put(ix::POS + 1, ix::YAW, dp[0]);
    for i in 0..3 {
        for j in 0..3 {
            put(ix::VEL + i, ix::ACCEL_BIAS + j, -r[(i, j)] * dt);
        }
    }
    put(ix::YAW, ix::GYRO_Z_BIAS, -yaw_gain * dt);
    // Tilt error phi: true specific force in the world is (I + [phi]x) R f, so
    // d(v)/d(phi) = -[R f]x, for the x and y columns.
    put(ix::VEL, ix::TILT + 1, u.z * dt);
    put(ix::VEL + 1, ix::TILT, -u.z * dt);
    put(ix::VEL + 2, ix::TILT, u.y * dt);
    put(ix::VEL + 2, ix::TILT + 1, -u.x * dt);
    // A gyro bias error b turns the estimate by b dt in the body: d(phi)/d(b) = -R.
    for i in 0..2 {
        for j in 0..2 {
            put(ix::TILT + i, ix::GYRO_XY_BIAS + j, -r[(i, j)] * dt);
        }
    }
    g
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::estimate::ekf::{Covariance, EkfConfig};

    /// A level vehicle at rest (or hovering): gravity on z, no rotation.
    pub(crate) fn hover_step() -> ImuStep {
        ImuStep {
            accel_m_s2: [0.0, 0.0, GRAVITY_M_S2],
            gyro_rad_s: [0.0; 3],
            tilt: Tilt::LEVEL,
        }
    }

    /// The rotation at a roll, pitch and yaw (rad).
    pub(crate) fn rotation_at(roll: f32, pitch: f32, yaw: f32) -> Matrix3<f32> {
        rotation(&Tilt::from_angles(roll, pitch), libm::sincosf(yaw))
    }

    #[test]
    fn rotation_is_orthonormal_and_matches_the_tilt_convention() {
        let r = rotation_at(0.3, -0.2, 1.0);
        assert!((r * r.transpose() - Matrix3::identity()).norm() < 1e-5);
        // Positive pitch tips body z toward world +x; positive roll tips it toward -y.
        assert!(rotation_at(0.0, 0.2, 0.0)[(0, 2)] > 0.0);
        assert!(rotation_at(0.2, 0.0, 0.0)[(1, 2)] < 0.0);
    }

    #[test]
    fn sparse_propagation_equals_the_dense_product() {
        let mut f = Ekf::new(EkfConfig::default());
        // A full, symmetric covariance so every entry of the product matters.
        for i in 0..N {
            for j in 0..N {
                f.p[(i, j)] = if i == j {
                    1.0
                } else {
                    0.01 * (i + 2 * j) as f32 / N as f32
                };
            }
        }
        f.p = (f.p + f.p.transpose()) * 0.5;
        let r = rotation_at(0.1, -0.2, 0.7);
        let u = Vector3::new(0.3, -0.4, 9.9);
        let mut dense = Covariance::identity();
        let moved = PendingMotion {
            dt: 0.01,
            velocity: [0.003, -0.004],
            position: [2e-5, 1e-5],
        };
        for (i, j, v) in jacobian_entries(&r, &u, 1.01, &moved) {
            dense[(i, j)] += v;
        }
        let expected = dense * f.p * dense.transpose();
        let mut no_noise = f;
        no_noise.config = EkfConfig {
            accel_noise_density: 0.0,
            gyro_noise_density: 0.0,
            accel_bias_walk: 0.0,
            gyro_bias_walk: 0.0,
            ..f.config
        };
        no_noise.propagate_covariance(&r, &u, 1.01, &moved);
        assert!((no_noise.p - expected).abs().max() < 1e-5);
    }

    #[test]
    fn hover_stays_put_and_uncertainty_grows() {
        let mut f = Ekf::new(EkfConfig::default());
        let p0 = f.covariance()[(ix::POS, ix::POS)];
        for _ in 0..500 {
            f.predict(&hover_step(), 0.002).unwrap();
        }
        assert!(f.state().fixed_rows::<6>(0).norm() < 1e-5);
        assert!(f.covariance()[(ix::POS, ix::POS)] > p0);
        assert!(f.covariance()[(ix::VEL, ix::VEL)] > 0.05 * 0.05);
    }

    #[test]
    fn tilted_thrust_accelerates_the_right_way() {
        let mut f = Ekf::new(EkfConfig::default());
        let tilt: f32 = 0.1;
        // Thrust that exactly holds height at this pitch: horizontal accel g tan(tilt), forward.
        let step = ImuStep {
            accel_m_s2: [0.0, 0.0, GRAVITY_M_S2 / libm::cosf(tilt)],
            tilt: Tilt::from_angles(0.0, tilt),
            ..hover_step()
        };
        for _ in 0..500 {
            f.predict(&step, 0.002).unwrap();
        }
        let v = f.state()[ix::VEL];
        assert!((v - GRAVITY_M_S2 * libm::tanf(tilt)).abs() < 1e-3, "{v}");
        assert!(f.state()[ix::VEL + 2].abs() < 1e-4);
    }

    #[test]
    fn yaw_integrates_the_bias_corrected_rate() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::GYRO_Z_BIAS] = 0.01;
        let step = ImuStep {
            gyro_rad_s: [0.0, 0.0, 0.51],
            ..hover_step()
        };
        for _ in 0..1000 {
            f.predict(&step, 0.001).unwrap();
        }
        assert!((f.state()[ix::YAW] - 0.5).abs() < 1e-4);
    }

    #[test]
    fn bad_samples_are_refused() {
        let mut f = Ekf::new(EkfConfig::default());
        let before = f;
        let nan = ImuStep {
            tilt: Tilt::from_angles(f32::NAN, 0.0),
            ..hover_step()
        };
        assert_eq!(f.predict(&nan, 0.002), Err(PredictError::NonFinite));
        assert_eq!(f.predict(&hover_step(), 0.0), Err(PredictError::BadDt));
        assert_eq!(
            f.predict(&hover_step(), f32::INFINITY),
            Err(PredictError::BadDt)
        );
        assert_eq!(f, before);
    }
}
