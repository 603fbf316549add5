//! Rigid-body quadrotor dynamics (seed 002 eqs. 13-19) with the seed's second-order motor model:
//! the body by fixed-step fourth-order Runge-Kutta, the motors in closed form ([`crate::vehicle::motors`]).
//!
//! Differences from the seed's text, and why:
//! - Frames are FLU body / ENU-like world (DESIGN.md §3), so thrust is +z body and rotor numbering
//!   is mapped as described in [`crate::vehicle`].
//! - Translation is integrated as world-frame velocity, m dv/dt = R (0,0,Στ) + m g + F: eq. 13
//!   written in the inertial frame (the ω × m v term disappears), which keeps RK4 exact for free
//!   fall and uniform motion.
//! - Eq. 14 is kept in full: I ω̇ = M - ω × I ω - ω × h - ḣ with h = Σ s_i I_r Ω_i ẑ the rotor
//!   angular momentum. -ḣ is the inertial reaction (eq. 17) and -ω × h the gyroscopic moment
//!   (eq. 18); written this way angular momentum is conserved exactly when no external moment acts.
//! - The seed neglects aerodynamics near hover; we add linear (rotor) and quadratic (fuselage) drag
//!   on the air-relative velocity and rotational damping, so gusts have something to push on.
//! - The motor stages do not feed back from the body, so they are solved exactly over the step
//!   and the body's RK4 stages read the rotors at t, t + dt/2 and t + dt: the rotor terms are
//!   evaluated three times a step instead of four, and the body carries 13 states, not 21.

use crate::math::{Quat, Vec3};
use crate::vehicle::model_error::{ModelError, TrueBody};
use crate::vehicle::motors::{MotorModel, Rotors};
use crate::vehicle::{VehicleParams, GRAVITY};
use core::cell::Cell;

/// The integrated state: body pose and rates, the two motor stages of each rotor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyState {
    /// Centre of gravity in the world frame, m.
    pub position: Vec3,
    /// World-frame velocity, m/s.
    pub velocity: Vec3,
    /// Body to world rotation.
    pub attitude: Quat,
    /// Body rates (p, q, r), rad/s.
    pub rate: Vec3,
    /// First motor stage (normalised 0..1, the seed's "motor state").
    pub motor: [f64; 4],
    /// Rotor speeds Ω_i, rad/s (magnitudes; the spin direction is the rotor's).
    pub rotor_speed: [f64; 4],
}

impl BodyState {
    /// At rest at `position` with heading `yaw`, rotors stopped.
    pub fn at_rest(position: Vec3, yaw: f64) -> Self {
        Self {
            position,
            attitude: Quat::from_euler(0.0, 0.0, yaw),
            ..Self::default()
        }
    }

    /// No NaN or infinity anywhere. Checked every step, so by one sum: a NaN or an infinity in
    /// any term makes the sum non-finite. (So would finite terms near 1e308 overflowing it,
    /// which is no less a diverged state.)
    pub fn is_finite(&self) -> bool {
        let q = self.attitude;
        let sum = (self.position + self.velocity + self.rate).dot(Vec3::new(1.0, 1.0, 1.0))
            + (q.w + q.x + q.y + q.z)
            + self.motor.iter().sum::<f64>()
            + self.rotor_speed.iter().sum::<f64>();
        sum.is_finite()
    }

    fn rotors(&self) -> Rotors {
        Rotors {
            motor: self.motor,
            speed: self.rotor_speed,
        }
    }
}

/// The rigid-body part of the state, which RK4 integrates.
#[derive(Clone, Copy, Debug)]
struct Rigid {
    position: Vec3,
    velocity: Vec3,
    attitude: Quat,
    rate: Vec3,
}

impl Rigid {
    /// `self + d * h` for an RK4 stage.
    fn add_scaled(&self, d: &Rigid, h: f64) -> Rigid {
        Rigid {
            position: self.position + d.position * h,
            velocity: self.velocity + d.velocity * h,
            attitude: self.attitude.add_scaled(d.attitude, h),
            rate: self.rate + d.rate * h,
        }
    }

    /// `a + b` component-wise, for summing RK4 slopes.
    fn sum(&self, o: &Rigid) -> Rigid {
        self.add_scaled(o, 1.0)
    }

    /// RK4's final combination, `self + (k1 + 2 k2 + 2 k3 + k4) h / 6`. Kept out of line on
    /// purpose, the one call in the step: inlined, the compiler carries the slopes (and their
    /// partial sums) in registers through the later stages, copying and spilling them; as a
    /// call's arguments each slope goes to the stack once, whole. Measured (rustc 1.95, x86-64):
    /// the RK4 step 1,136 -> 1,059 instructions, 395 -> 294 register copies, about 18 % less
    /// CPU; the office survey 8 % less CPU. Same operations in the same order: bit-identical.
    #[inline(never)]
    fn combine(&self, k1: &Rigid, k2: &Rigid, k3: &Rigid, k4: &Rigid, h: f64) -> Rigid {
        self.add_scaled(&k1.sum(k4).add_scaled(&k2.sum(k3), 2.0), h / 6.0)
    }
}

/// What the rotors do to the body at one instant (body frame).
#[derive(Clone, Copy, Debug)]
struct RotorWrench {
    thrust: f64,
    /// Differential thrust (eq. 16), hub moments (eq. 15) and the inertial reaction -ḣ (eq. 17).
    moment: Vec3,
    /// h_z = Σ s_i I_r Ω_i, for the gyroscopic moment (eq. 18).
    momentum: f64,
}

/// What acts on the vehicle during one step (held constant over the step).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Forcing {
    /// Motor commands x_i, clamped to 0..1.
    pub command: [f64; 4],
    /// Air velocity in the world frame (gusts), m/s.
    pub wind: Vec3,
    /// External force in the world frame (pushes, seed 000 sec. 4.3), N.
    pub force: Vec3,
}

/// The dynamics of one vehicle at one step length, constants precomputed: the rotor terms are
/// per-rotor weights of Ω² and Ω, so each is a four-term dot product.
#[derive(Clone, Debug)]
pub struct Dynamics {
    dt: f64,
    /// The rotors the last step ended with and their wrench: the next step usually starts
    /// there, and the wrench is a pure function of the rotors, so it is reused when they match.
    last_end: Cell<Option<(Rotors, RotorWrench)>>,
    motors: MotorModel,
    /// Per-rotor k_T, with the motor mismatch applied.
    thrust_coeff: [f64; 4],
    /// Roll, pitch and yaw moment per Ω²: y_i k_T, -x_i k_T (r × (0, 0, τ)) and -s_i k_M.
    roll_coeff: [f64; 4],
    pitch_coeff: [f64; 4],
    yaw_coeff: [f64; 4],
    /// s_i I_r: rotor angular momentum per unit speed.
    momentum_coeff: [f64; 4],
    inertia: Vec3,
    /// 1/I and 1/m: the derivative runs four times a step.
    inv_inertia: Vec3,
    inv_mass: f64,
    drag_linear: f64,
    drag_quadratic: f64,
    drag_rotational: f64,
}

fn dot4(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    (a[0] * b[0] + a[1] * b[1]) + (a[2] * b[2] + a[3] * b[3])
}

impl Dynamics {
    /// `mismatch[i]` scales rotor i's thrust coefficient (1.0 = nominal); `dt_s` is the step.
    #[inline]
    pub fn new(p: &VehicleParams, mismatch: [f64; 4], dt_s: f64) -> Self {
        Self::with_body(p, &ModelError::NONE.body(p, true), mismatch, dt_s)
    }

    /// The dynamics of `body` (the nominal vehicle `p` with a model error applied):
    /// `mismatch[i]` scales rotor i's thrust coefficient on top of the body's rotor factor,
    /// which scales its hub moment too; rotor arms are measured from the body's centre of
    /// gravity. Inlined so that the runner builds the constants in its own frame: 25 M fewer
    /// instructions over the office survey than with a call (measured, not derived).
    #[inline]
    pub fn with_body(p: &VehicleParams, body: &TrueBody, mismatch: [f64; 4], dt_s: f64) -> Self {
        let rotors = p.rotors();
        let factor = body.rotor_factor;
        let thrust_coeff: [f64; 4] =
            core::array::from_fn(|i| p.thrust_coeff * mismatch[i] * factor[i]);
        let [cg_x, cg_y] = body.cg_offset_m;
        let inertia = body.inertia_kgm2;
        Self {
            dt: dt_s,
            last_end: Cell::new(None),
            motors: MotorModel::new(p.motor_tau_s, p.rotor_tau_s, p.max_rotor_speed_radps, dt_s),
            thrust_coeff,
            roll_coeff: core::array::from_fn(|i| (rotors[i].position_m.y - cg_y) * thrust_coeff[i]),
            pitch_coeff: core::array::from_fn(|i| {
                -(rotors[i].position_m.x - cg_x) * thrust_coeff[i]
            }),
            yaw_coeff: core::array::from_fn(|i| -rotors[i].spin * (p.moment_coeff * factor[i])),
            momentum_coeff: rotors.map(|r| r.spin * p.rotor_inertia_kgm2),
            inertia: Vec3::new(inertia[0], inertia[1], inertia[2]),
            inv_inertia: Vec3::new(1.0 / inertia[0], 1.0 / inertia[1], 1.0 / inertia[2]),
            inv_mass: 1.0 / body.mass_kg,
            drag_linear: p.drag_linear,
            drag_quadratic: p.drag_quadratic,
            drag_rotational: p.drag_rotational,
        }
    }

    /// The four linear rows in Ω_i² that a hover must satisfy (total thrust, roll, pitch and
    /// yaw moment), and the weight the first must equal, N: see [`crate::vehicle::still_hover`].
    pub(crate) fn hover_rows(&self) -> ([[f64; 4]; 4], f64) {
        let rows = [
            self.thrust_coeff,
            self.roll_coeff,
            self.pitch_coeff,
            self.yaw_coeff,
        ];
        (rows, GRAVITY / self.inv_mass)
    }

    /// Thrust of each rotor, τ_i = k_T Ω_i², N.
    pub fn thrusts(&self, s: &BodyState) -> [f64; 4] {
        core::array::from_fn(|i| self.thrust_coeff[i] * s.rotor_speed[i] * s.rotor_speed[i])
    }

    /// dΩ_i/dt of the second motor stage, rad/s².
    pub fn rotor_acceleration(&self, s: &BodyState) -> [f64; 4] {
        self.motors.acceleration(&s.rotors())
    }

    /// Seed 002 eqs. 15-17 for the rotors in state `r`.
    #[inline(always)]
    fn wrench(&self, r: &Rotors) -> RotorWrench {
        let w2 = r.speed.map(|w| w * w);
        let accel = self.motors.acceleration(r);
        RotorWrench {
            thrust: dot4(&self.thrust_coeff, &w2),
            moment: Vec3::new(
                dot4(&self.roll_coeff, &w2),
                dot4(&self.pitch_coeff, &w2),
                dot4(&self.yaw_coeff, &w2) - dot4(&self.momentum_coeff, &accel),
            ),
            momentum: dot4(&self.momentum_coeff, &r.speed),
        }
    }

    /// The time derivative of the rigid body (eqs. 13, 14, 18 and the quaternion kinematics).
    #[inline(always)]
    fn slope(&self, s: &Rigid, f: &Forcing, r: &RotorWrench) -> Rigid {
        let w = s.rate;
        // Eq. 14: -ω × I ω, and -ω × h with h = (0, 0, h_z), plus rotational damping.
        let net = r.moment - w.cross(w.scale(self.inertia))
            + Vec3::new(-w.y * r.momentum, w.x * r.momentum, 0.0)
            - w * self.drag_rotational;
        let air = s.velocity - f.wind;
        let drag = air * -(self.drag_linear + self.drag_quadratic * air.norm());
        let force = s.attitude.z_axis() * r.thrust + drag + f.force;
        Rigid {
            position: s.velocity,
            velocity: force * self.inv_mass - Vec3::Z * GRAVITY,
            attitude: s.attitude.derivative(w),
            rate: net.scale(self.inv_inertia),
        }
    }

    /// One step: the motors in closed form, the body by classical RK4. The quaternion is
    /// renormalised afterwards by [`Quat::renormalized`] (one step drifts it by far less than
    /// 1e-8). Commands are clamped to 0..1 here, once. Inlined with its helpers into the
    /// runner's loop (see the runner's `lockstep` module), apart from the final combination (`Rigid::combine`).
    #[inline(always)]
    pub fn step(&self, s: &BodyState, f: &Forcing) -> BodyState {
        let f = &Forcing {
            command: f.command.map(|c| c.clamp(0.0, 1.0)),
            ..*f
        };
        let now = s.rotors();
        let mid = self.motors.half_step(&now, &f.command);
        let end = self.motors.full_step(&now, &f.command);
        let w_now = match self.last_end.get() {
            Some((r, w)) if r == now => w,
            _ => self.wrench(&now),
        };
        let (w_mid, w_end) = (self.wrench(&mid), self.wrench(&end));
        self.last_end.set(Some((end, w_end)));
        let b = Rigid {
            position: s.position,
            velocity: s.velocity,
            attitude: s.attitude,
            rate: s.rate,
        };
        let h = self.dt;
        let k1 = self.slope(&b, f, &w_now);
        let k2 = self.slope(&b.add_scaled(&k1, 0.5 * h), f, &w_mid);
        let k3 = self.slope(&b.add_scaled(&k2, 0.5 * h), f, &w_mid);
        let k4 = self.slope(&b.add_scaled(&k3, h), f, &w_end);
        let n = b.combine(&k1, &k2, &k3, &k4, h);
        BodyState {
            position: n.position,
            velocity: n.velocity,
            attitude: n.attitude.renormalized(),
            rate: n.rate,
            motor: end.motor,
            rotor_speed: end.speed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::Frame;

    fn bare(p: &VehicleParams) -> Dynamics {
        Dynamics::new(p, [1.0; 4], 1e-3)
    }

    /// A state whose motors sit in steady state at command `cmd`.
    fn spinning(p: &VehicleParams, cmd: [f64; 4]) -> BodyState {
        BodyState {
            motor: cmd,
            rotor_speed: cmd.map(|c| c * p.max_rotor_speed_radps),
            ..BodyState::at_rest(Vec3::new(0.0, 0.0, 1.0), 0.0)
        }
    }

    #[test]
    fn hover_command_gives_thrust_equal_to_weight_and_stays_put() {
        for frame in [Frame::X, Frame::Plus] {
            let p = VehicleParams {
                frame,
                ..VehicleParams::pelican()
            };
            let dynamics = bare(&p);
            let cmd = [p.hover_rotor_speed() / p.max_rotor_speed_radps; 4];
            let mut s = spinning(&p, cmd);
            let total: f64 = dynamics.thrusts(&s).iter().sum();
            assert!((total - p.mass_kg * GRAVITY).abs() < 1e-9, "thrust {total}");
            let f = Forcing {
                command: cmd,
                ..Forcing::default()
            };
            for _ in 0..5000 {
                s = dynamics.step(&s, &f);
            }
            assert!(
                (s.position - Vec3::new(0.0, 0.0, 1.0)).norm() < 1e-9,
                "{:?}",
                s.position
            );
            assert!(
                s.rate.norm() < 1e-12,
                "balanced hover must not rotate: {:?}",
                s.rate
            );
        }
    }

    #[test]
    fn free_fall_matches_the_closed_form() {
        let p = VehicleParams {
            drag_linear: 0.0,
            drag_quadratic: 0.0,
            ..VehicleParams::f450()
        };
        let dynamics = bare(&p);
        let mut s = BodyState {
            velocity: Vec3::new(1.0, 0.0, 2.0),
            ..BodyState::at_rest(Vec3::new(0.0, 0.0, 10.0), 0.3)
        };
        let f = Forcing::default();
        for _ in 0..1000 {
            s = dynamics.step(&s, &f);
        }
        let z = 10.0 + 2.0 - 0.5 * GRAVITY;
        assert!((s.position.z - z).abs() < 1e-9 && (s.position.x - 1.0).abs() < 1e-9);
        assert!((s.velocity.z - (2.0 - GRAVITY)).abs() < 1e-9);
    }

    #[test]
    fn torque_free_spin_conserves_angular_momentum_including_rotors() {
        // No thrust or hub moment, rotors spinning steadily: only eq. 14's coupling terms and the
        // gyroscopic moment (eq. 18) act, so world-frame angular momentum must stay constant.
        let p = VehicleParams {
            thrust_coeff: 0.0,
            moment_coeff: 0.0,
            drag_rotational: 0.0,
            inertia_kgm2: [0.01, 0.015, 0.022],
            ..VehicleParams::f450()
        };
        let dynamics = bare(&p);
        let cmd = [0.6, 0.3, 0.6, 0.2];
        let mut s = BodyState {
            rate: Vec3::new(1.0, -2.0, 0.7),
            ..spinning(&p, cmd)
        };
        let f = Forcing {
            command: cmd,
            ..Forcing::default()
        };
        let momentum = |s: &BodyState| {
            let h: f64 = (0..4)
                .map(|i| p.rotors()[i].spin * p.rotor_inertia_kgm2 * s.rotor_speed[i])
                .sum();
            s.attitude.rotate(s.rate.scale(p.inertia()) + Vec3::Z * h)
        };
        let l0 = momentum(&s);
        let e0 = s.rate.dot(s.rate.scale(p.inertia()));
        for _ in 0..10_000 {
            s = dynamics.step(&s, &f);
        }
        assert!(
            (momentum(&s) - l0).norm() < 1e-8 * l0.norm(),
            "{:?} vs {l0:?}",
            momentum(&s)
        );
        assert!(
            s.rate.dot(s.rate.scale(p.inertia())) > 0.5 * e0,
            "still spinning"
        );
        assert!(
            s.rate.x != 1.0,
            "the spin axis must have moved (not a trivial steady spin)"
        );
    }

    #[test]
    fn yaw_sign_follows_the_hub_moments() {
        // Speeding up the clockwise rotors (1 and 3) makes the body turn counter-clockwise.
        let p = VehicleParams::pelican();
        let dynamics = bare(&p);
        let h = p.hover_rotor_speed() / p.max_rotor_speed_radps;
        let cmd = [h * 1.05, h * 0.95, h * 1.05, h * 0.95];
        let mut s = spinning(&p, cmd);
        let f = Forcing {
            command: cmd,
            ..Forcing::default()
        };
        for _ in 0..300 {
            s = dynamics.step(&s, &f);
        }
        assert!(
            s.rate.z > 0.05 && s.attitude.yaw() > 0.0,
            "yaw rate {}",
            s.rate.z
        );
        assert!(s.rate.x.abs() < 1e-9 && s.rate.y.abs() < 1e-9);
    }

    #[test]
    fn differential_thrust_rolls_and_pitches_the_right_way() {
        // One step from rest: the rate it builds up has the sign of the angular acceleration.
        let p = VehicleParams::pelican();
        let dynamics = bare(&p);
        let h = p.hover_rotor_speed() / p.max_rotor_speed_radps;
        // Left rotors (3, 4) faster: roll right-side-down is positive roll in FLU.
        let roll_cmd = [h * 0.98, h * 0.98, h * 1.02, h * 1.02];
        let s = spinning(&p, roll_cmd);
        let d = dynamics.step(
            &s,
            &Forcing {
                command: roll_cmd,
                ..Forcing::default()
            },
        );
        assert!(d.rate.x > 0.0 && d.rate.y.abs() < 1e-9);
        // Back rotors (2, 3) faster: nose down, which is positive pitch in FLU.
        let pitch_cmd = [h * 0.98, h * 1.02, h * 1.02, h * 0.98];
        let s = spinning(&p, pitch_cmd);
        let d = dynamics.step(
            &s,
            &Forcing {
                command: pitch_cmd,
                ..Forcing::default()
            },
        );
        assert!(d.rate.y > 0.0 && d.rate.x.abs() < 1e-9);
    }

    #[test]
    fn motors_follow_two_cascaded_first_order_stages() {
        let p = VehicleParams::f450();
        let dynamics = bare(&p);
        let mut s = BodyState::at_rest(Vec3::new(0.0, 0.0, 100.0), 0.0);
        let f = Forcing {
            command: [1.0, 1.0, 1.0, 1.0],
            ..Forcing::default()
        };
        let t = 0.05;
        for _ in 0..50 {
            s = dynamics.step(&s, &f);
        }
        // Step response of 1/((τ1 s + 1)(τ2 s + 1)).
        let (a, b) = (p.motor_tau_s, p.rotor_tau_s);
        let expect = 1.0 - (a * (-t / a).exp() - b * (-t / b).exp()) / (a - b);
        let got = s.rotor_speed[0] / p.max_rotor_speed_radps;
        assert!((got - expect).abs() < 1e-6, "{got} vs {expect}");
        assert!((s.motor[0] - (1.0 - (-t / a).exp())).abs() < 1e-6);
    }
}
