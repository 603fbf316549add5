//! The ground-truth test pilot: a geometric tracking controller that reads the *true* state.
//!
//! It exists only so the simulator can fly scripted paths before (and independently of) the
//! onboard flight stack; nothing onboard may use it. Position error → desired acceleration →
//! desired thrust direction and heading → attitude error (quaternion) → moments, then the
//! vehicle's own allocation (the inverse of seed 002 eqs. 15-16 for its rotor layout) gives
//! rotor speeds, and the steady state of the motor model (Ω = Ω_max x) gives commands.

use crate::math::{Quat, Vec3};
use crate::runner::plan::Reference;
use crate::vehicle::dynamics::BodyState;
use crate::vehicle::{VehicleParams, GRAVITY};

/// Position errors beyond this are not integrated, m.
const INTEGRAL_GATE_M: f64 = 0.5;
/// Velocity errors beyond this (still chasing the reference) are not integrated, m/s.
const INTEGRAL_GATE_MPS: f64 = 0.1;
/// The most acceleration the integral term may command, m/s².
const MAX_INTEGRAL_ACCEL: f64 = 1.0;

/// The test pilot's gains and the allocation it inverts.
#[derive(Clone, Debug)]
pub struct TestPilot {
    mass: f64,
    inertia: Vec3,
    max_speed: f64,
    /// Maps (thrust, Mx, My, Mz) to Ω².
    allocation_inv: [[f64; 4]; 4],
    pos_gain: f64,
    vel_gain: f64,
    int_gain: f64,
    att_bandwidth: f64,
    att_damping: f64,
    yaw_bandwidth: f64,
    max_tilt_accel: f64,
    integral: Vec3,
}

/// Inverts a 4x4 matrix by Gauss-Jordan elimination with partial pivoting.
fn invert4(m: [[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut a = m;
    let mut inv = [[0.0; 4]; 4];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for col in 0..4 {
        let pivot = (col..4).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() < 1e-15 {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = a[col][col];
        for k in 0..4 {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for r in 0..4 {
            if r != col {
                let f = a[r][col];
                for k in 0..4 {
                    a[r][k] -= f * a[col][k];
                    inv[r][k] -= f * inv[col][k];
                }
            }
        }
    }
    Some(inv)
}

impl TestPilot {
    /// Gains scale with the vehicle's inertia; `None` if the rotor layout cannot be inverted.
    pub fn new(p: &VehicleParams) -> Option<Self> {
        let rotors = p.rotors();
        let mut a = [[0.0; 4]; 4];
        for (i, r) in rotors.iter().enumerate() {
            a[0][i] = p.thrust_coeff;
            a[1][i] = p.thrust_coeff * r.position_m.y;
            a[2][i] = -p.thrust_coeff * r.position_m.x;
            a[3][i] = -r.spin * p.moment_coeff;
        }
        Some(Self {
            mass: p.mass_kg,
            inertia: p.inertia(),
            max_speed: p.max_rotor_speed_radps,
            allocation_inv: invert4(a)?,
            pos_gain: 2.5,
            vel_gain: 3.0,
            int_gain: 1.0,
            att_bandwidth: 10.0,
            att_damping: 0.9,
            yaw_bandwidth: 4.0,
            max_tilt_accel: 0.45 * GRAVITY,
            integral: Vec3::ZERO,
        })
    }

    /// Motor commands (0..1) that track `r` from the true state `s`.
    pub fn command(&mut self, s: &BodyState, r: &Reference, dt_s: f64) -> [f64; 4] {
        if r.finished && s.position.z < 0.05 {
            self.integral = Vec3::ZERO;
            return [0.0; 4];
        }
        let e_p = r.position - s.position;
        // Integrate only when settled near the reference (close, and not chasing it), and bound
        // what the integral may ask for, so a large step does not wind up; the position gate is
        // wide enough that the steady offset the unmodelled motor mismatch causes (tens of
        // centimetres) is still integrated away.
        let e_v = r.velocity - s.velocity;
        if e_p.norm() < INTEGRAL_GATE_M && e_v.norm() < INTEGRAL_GATE_MPS {
            self.integral += e_p * dt_s;
            let demand = self.integral.norm() * self.int_gain;
            if demand > MAX_INTEGRAL_ACCEL {
                self.integral = self.integral * (MAX_INTEGRAL_ACCEL / demand);
            }
        }
        let mut acc = e_p * self.pos_gain
            + e_v * self.vel_gain
            + self.integral * self.int_gain
            + r.acceleration;
        let h = (acc.x * acc.x + acc.y * acc.y).sqrt();
        if h > self.max_tilt_accel {
            acc.x *= self.max_tilt_accel / h;
            acc.y *= self.max_tilt_accel / h;
        }
        acc.z = acc.z.max(-0.7 * GRAVITY);
        let f = acc + Vec3::Z * GRAVITY;
        let b3_des = f * (1.0 / f.norm());
        let b3 = s.attitude.rotate(Vec3::Z);
        let thrust = self.mass * f.dot(b3).max(0.0);
        // Desired attitude: the tilt taking world z to b3_des, after the heading rotation.
        let tilt = Quat {
            w: 1.0 + b3_des.z,
            x: -b3_des.y,
            y: b3_des.x,
            z: 0.0,
        }
        .normalized();
        let q_des = tilt * Quat::from_euler(0.0, 0.0, r.yaw);
        let q_err = q_des.conj() * s.attitude;
        let sign = if q_err.w < 0.0 { -2.0 } else { 2.0 };
        let e_r = Vec3::new(q_err.x, q_err.y, q_err.z) * sign;
        // Yaw authority (hub moments) is an order of magnitude below roll and pitch authority:
        // a gentler, bounded yaw loop keeps heading changes from saturating the rotors.
        let e_r = Vec3::new(e_r.x, e_r.y, e_r.z.clamp(-0.3, 0.3));
        let gain = |wn: f64| (wn * wn, 2.0 * self.att_damping * wn);
        let (kr, kw) = gain(self.att_bandwidth);
        let (kr_yaw, kw_yaw) = gain(self.yaw_bandwidth);
        let (i, w) = (self.inertia, s.rate);
        let gyro = w.cross(w.scale(i));
        let moment = Vec3::new(
            -i.x * (kr * e_r.x + kw * w.x) + gyro.x,
            -i.y * (kr * e_r.y + kw * w.y) + gyro.y,
            -i.z * (kr_yaw * e_r.z + kw_yaw * w.z) + gyro.z,
        );
        self.allocate([thrust, moment.x, moment.y, moment.z])
    }

    /// Rotor commands for a wrench; when the rotors would saturate, the yaw moment is scaled
    /// down first so that thrust and attitude keep their authority.
    fn allocate(&self, wrench: [f64; 4]) -> [f64; 4] {
        let max2 = self.max_speed * self.max_speed;
        let inv = &self.allocation_inv;
        let base: [f64; 4] = core::array::from_fn(|k| (0..3).map(|j| inv[k][j] * wrench[j]).sum());
        let yaw: [f64; 4] = core::array::from_fn(|k| inv[k][3] * wrench[3]);
        let mut alpha: f64 = 1.0;
        for k in 0..4 {
            if base[k] + yaw[k] > max2 && yaw[k] > 0.0 {
                alpha = alpha.min(((max2 - base[k]) / yaw[k]).max(0.0));
            }
            if base[k] + yaw[k] < 0.0 && yaw[k] < 0.0 {
                alpha = alpha.min((base[k] / -yaw[k]).max(0.0));
            }
        }
        core::array::from_fn(|k| {
            ((base[k] + alpha * yaw[k]).max(0.0).sqrt() / self.max_speed).clamp(0.0, 1.0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::dynamics::{Dynamics, Forcing};
    use crate::vehicle::Frame;

    #[test]
    fn allocation_inverse_is_an_inverse() {
        let m = [
            [2.0, 1.0, 0.0, 0.0],
            [1.0, 3.0, 1.0, 0.0],
            [0.0, 1.0, 4.0, 1.0],
            [0.5, 0.0, 1.0, 5.0],
        ];
        let inv = invert4(m).unwrap();
        for (r, row) in m.iter().enumerate() {
            for c in 0..4 {
                let v: f64 = row
                    .iter()
                    .zip(&inv)
                    .map(|(a, inv_row)| a * inv_row[c])
                    .sum();
                assert!((v - if r == c { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        assert!(invert4([[1.0; 4]; 4]).is_none());
    }

    #[test]
    fn pilot_steps_one_metre_and_turns_in_both_frames() {
        for frame in [Frame::X, Frame::Plus] {
            let p = VehicleParams {
                frame,
                ..VehicleParams::f450()
            };
            let dynamics = Dynamics::new(&p, [1.0; 4], 1e-3);
            let mut pilot = TestPilot::new(&p).unwrap();
            let h = p.hover_rotor_speed();
            let mut s = BodyState {
                motor: [h / p.max_rotor_speed_radps; 4],
                rotor_speed: [h; 4],
                ..BodyState::at_rest(Vec3::new(0.0, 0.0, 1.0), 0.0)
            };
            let r = Reference {
                position: Vec3::new(1.0, -1.0, 1.5),
                yaw: 1.0,
                ..Reference::default()
            };
            for _ in 0..8000 {
                let cmd = pilot.command(&s, &r, 1e-3);
                s = dynamics.step(
                    &s,
                    &Forcing {
                        command: cmd,
                        ..Forcing::default()
                    },
                );
            }
            assert!(
                (s.position - r.position).norm() < 0.02,
                "{frame:?}: {:?}",
                s.position
            );
            assert!(
                (s.attitude.yaw() - 1.0).abs() < 0.02,
                "{frame:?}: yaw {}",
                s.attitude.yaw()
            );
        }
    }
}
