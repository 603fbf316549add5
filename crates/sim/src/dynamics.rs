//! Rigid-body quadrotor dynamics (seed 002 eqs. 13-19) with the seed's second-order motor model,
//! integrated by fixed-step fourth-order Runge-Kutta.
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

use crate::math::{Quat, Vec3};
use crate::vehicle::{Rotor, VehicleParams, GRAVITY};

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

    pub fn is_finite(&self) -> bool {
        self.position.is_finite()
            && self.velocity.is_finite()
            && self.attitude.is_finite()
            && self.rate.is_finite()
            && self
                .rotor_speed
                .iter()
                .chain(&self.motor)
                .all(|v| v.is_finite())
    }

    /// `self + d * h` for an RK4 stage.
    fn add_scaled(&self, d: &BodyState, h: f64) -> BodyState {
        BodyState {
            position: self.position + d.position * h,
            velocity: self.velocity + d.velocity * h,
            attitude: self.attitude.add_scaled(d.attitude, h),
            rate: self.rate + d.rate * h,
            motor: core::array::from_fn(|i| self.motor[i] + d.motor[i] * h),
            rotor_speed: core::array::from_fn(|i| self.rotor_speed[i] + d.rotor_speed[i] * h),
        }
    }
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

/// The dynamics of one vehicle, constants precomputed.
#[derive(Clone, Debug)]
pub struct Dynamics {
    inertia: Vec3,
    rotors: [Rotor; 4],
    /// Per-rotor k_T, with the motor mismatch applied.
    thrust_coeff: [f64; 4],
    moment_coeff: f64,
    rotor_inertia: f64,
    max_speed: f64,
    /// 1/τ of the two motor stages and 1/I, 1/m: the derivative runs four times a step.
    inv_motor_tau: f64,
    inv_rotor_tau: f64,
    inv_inertia: Vec3,
    inv_mass: f64,
    drag_linear: f64,
    drag_quadratic: f64,
    drag_rotational: f64,
}

impl Dynamics {
    /// `mismatch[i]` scales rotor i's thrust coefficient (1.0 = nominal).
    pub fn new(p: &VehicleParams, mismatch: [f64; 4]) -> Self {
        Self {
            inertia: p.inertia(),
            rotors: p.rotors(),
            thrust_coeff: mismatch.map(|m| p.thrust_coeff * m),
            moment_coeff: p.moment_coeff,
            rotor_inertia: p.rotor_inertia_kgm2,
            max_speed: p.max_rotor_speed_radps,
            inv_motor_tau: 1.0 / p.motor_tau_s,
            inv_rotor_tau: 1.0 / p.rotor_tau_s,
            inv_inertia: Vec3::new(
                1.0 / p.inertia_kgm2[0],
                1.0 / p.inertia_kgm2[1],
                1.0 / p.inertia_kgm2[2],
            ),
            inv_mass: 1.0 / p.mass_kg,
            drag_linear: p.drag_linear,
            drag_quadratic: p.drag_quadratic,
            drag_rotational: p.drag_rotational,
        }
    }

    /// Thrust of each rotor, τ_i = k_T Ω_i², N.
    pub fn thrusts(&self, s: &BodyState) -> [f64; 4] {
        core::array::from_fn(|i| self.thrust_coeff[i] * s.rotor_speed[i] * s.rotor_speed[i])
    }

    /// Shaft torque of each rotor (the hub yawing moment magnitude M_i = k_M Ω_i²), N m.
    pub fn shaft_torques(&self, s: &BodyState) -> [f64; 4] {
        core::array::from_fn(|i| self.moment_coeff * s.rotor_speed[i] * s.rotor_speed[i])
    }

    /// dΩ_i/dt of the second motor stage, rad/s².
    pub fn rotor_acceleration(&self, s: &BodyState, i: usize) -> f64 {
        (self.max_speed * s.motor[i] - s.rotor_speed[i]) * self.inv_rotor_tau
    }

    /// Rotor inertia I_r, for the acceleration power of the rotors.
    pub fn rotor_inertia(&self) -> f64 {
        self.rotor_inertia
    }

    /// Force on the vehicle other than gravity, world frame, N.
    fn non_gravity_force(&self, s: &BodyState, f: &Forcing, thrust: f64) -> Vec3 {
        let air = s.velocity - f.wind;
        let drag = air * -(self.drag_linear + self.drag_quadratic * air.norm());
        s.attitude.z_axis() * thrust + drag + f.force
    }

    /// The time derivative of the state (seed 002 eqs. 13-19 and the motor model), for
    /// commands already in 0..1.
    pub fn derivative(&self, s: &BodyState, f: &Forcing) -> BodyState {
        let mut d = BodyState::default();
        let mut thrust = 0.0;
        let mut moment = Vec3::ZERO;
        let mut rotor_momentum = 0.0; // h_z = Σ s_i I_r Ω_i
        let mut rotor_momentum_rate = 0.0;
        for (i, rotor) in self.rotors.iter().enumerate() {
            d.motor[i] = (f.command[i] - s.motor[i]) * self.inv_motor_tau;
            d.rotor_speed[i] = self.rotor_acceleration(s, i);
            let w2 = s.rotor_speed[i] * s.rotor_speed[i];
            let tau = self.thrust_coeff[i] * w2;
            thrust += tau;
            // Differential thrust (eq. 16) and hub yawing moment (eq. 15): the air drags the
            // rotor against its spin, the body feels the reaction.
            // r × (0, 0, τ) = (y τ, -x τ, 0).
            moment.x += rotor.position_m.y * tau;
            moment.y -= rotor.position_m.x * tau;
            moment.z -= rotor.spin * self.moment_coeff * w2;
            rotor_momentum += rotor.spin * self.rotor_inertia * s.rotor_speed[i];
            rotor_momentum_rate += rotor.spin * self.rotor_inertia * d.rotor_speed[i];
        }
        let w = s.rate;
        let iw = w.scale(self.inertia);
        let h = Vec3::Z * rotor_momentum;
        // Eq. 14 with eqs. 17 (-ḣ) and 18 (-ω × h), plus rotational damping.
        let net = moment
            - w.cross(iw)
            - w.cross(h)
            - Vec3::Z * rotor_momentum_rate
            - w * self.drag_rotational;
        d.rate = net.scale(self.inv_inertia);
        d.position = s.velocity;
        d.velocity = self.non_gravity_force(s, f, thrust) * self.inv_mass - Vec3::Z * GRAVITY;
        d.attitude = s.attitude.derivative(w);
        d
    }

    /// One classical RK4 step of `dt` seconds; the quaternion is renormalised afterwards.
    /// Commands are clamped to 0..1 here, once, before the four stages.
    pub fn step(&self, s: &BodyState, f: &Forcing, dt: f64) -> BodyState {
        let f = &Forcing {
            command: f.command.map(|c| c.clamp(0.0, 1.0)),
            ..*f
        };
        let k1 = self.derivative(s, f);
        let k2 = self.derivative(&s.add_scaled(&k1, 0.5 * dt), f);
        let k3 = self.derivative(&s.add_scaled(&k2, 0.5 * dt), f);
        let k4 = self.derivative(&s.add_scaled(&k3, dt), f);
        let mut n = *s;
        let h6 = dt / 6.0;
        for (k, w) in [(&k1, 1.0), (&k2, 2.0), (&k3, 2.0), (&k4, 1.0)] {
            n = n.add_scaled(k, w * h6);
        }
        n.attitude = n.attitude.normalized();
        n
    }

    /// Specific force an accelerometer at the centre of gravity reads, body frame, m/s².
    pub fn specific_force(&self, s: &BodyState, f: &Forcing) -> Vec3 {
        let thrust: f64 = self.thrusts(s).iter().sum();
        s.attitude
            .rotate_inv(self.non_gravity_force(s, f, thrust) * self.inv_mass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::Frame;

    fn bare(p: &VehicleParams) -> Dynamics {
        Dynamics::new(p, [1.0; 4])
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
                s = dynamics.step(&s, &f, 1e-3);
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
            s = dynamics.step(&s, &f, 1e-3);
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
            s = dynamics.step(&s, &f, 1e-3);
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
            s = dynamics.step(&s, &f, 1e-3);
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
        let p = VehicleParams::pelican();
        let dynamics = bare(&p);
        let h = p.hover_rotor_speed() / p.max_rotor_speed_radps;
        // Left rotors (3, 4) faster: roll right-side-down is positive roll in FLU.
        let roll_cmd = [h * 0.98, h * 0.98, h * 1.02, h * 1.02];
        let s = spinning(&p, roll_cmd);
        let d = dynamics.derivative(
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
        let d = dynamics.derivative(
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
        let dt = 1e-3;
        let t = 0.05;
        for _ in 0..50 {
            s = dynamics.step(&s, &f, dt);
        }
        // Step response of 1/((τ1 s + 1)(τ2 s + 1)).
        let (a, b) = (p.motor_tau_s, p.rotor_tau_s);
        let expect = 1.0 - (a * (-t / a).exp() - b * (-t / b).exp()) / (a - b);
        let got = s.rotor_speed[0] / p.max_rotor_speed_radps;
        assert!((got - expect).abs() < 1e-6, "{got} vs {expect}");
        assert!((s.motor[0] - (1.0 - (-t / a).exp())).abs() < 1e-6);
    }
}
