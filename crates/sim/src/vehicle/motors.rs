//! The seed 002 motor model, two cascaded first-order stages from command to rotor speed, solved
//! in closed form over a physics step.
//!
//! Both stages are linear and the command is held over a step, so the exact solution costs a few
//! multiplications with constants computed once for the step length. That is cheaper than
//! carrying eight more states through every Runge-Kutta stage, and exact instead of fourth-order:
//! the rigid body's integrator then reads the rotor speeds at the times its stages need.
//!
//! With a = 1/τ_motor, b = 1/τ_rotor, Ω_max the speed at full command, command c held:
//! m' = a (c - m), Ω' = b (Ω_max m - Ω), hence after a time t
//! m(t) = c + (m₀ - c) e^(-a t),
//! Ω(t) = Ω_max c + (Ω₀ - Ω_max c) e^(-b t) + Ω_max (m₀ - c) b (e^(-a t) - e^(-b t)) / (b - a).

/// Decay factors for one time span.
#[derive(Clone, Copy, Debug)]
struct Decay {
    motor: f64,
    rotor: f64,
    /// b (e^(-a t) - e^(-b t)) / (b - a): how much of the motor stage's offset reaches the rotor.
    cross: f64,
}

impl Decay {
    fn over(a: f64, b: f64, t: f64) -> Self {
        let (ea, eb) = ((-a * t).exp(), (-b * t).exp());
        // Equal time constants: the limit b t e^(-b t).
        let cross = if (b - a).abs() <= 1e-9 * b.max(a) {
            b * t * eb
        } else {
            b * (ea - eb) / (b - a)
        };
        Self {
            motor: ea,
            rotor: eb,
            cross,
        }
    }
}

/// The four motor stages and rotor speeds at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotors {
    /// First stage, normalised 0..1.
    pub motor: [f64; 4],
    /// Rotor speeds Ω_i, rad/s.
    pub speed: [f64; 4],
}

/// The motor model for a fixed step length.
#[derive(Clone, Debug)]
pub struct MotorModel {
    max_speed: f64,
    inv_rotor_tau: f64,
    half: Decay,
    full: Decay,
}

impl MotorModel {
    /// Time constants of the two stages (s), full-command speed (rad/s), step length (s).
    pub fn new(motor_tau_s: f64, rotor_tau_s: f64, max_speed_radps: f64, dt_s: f64) -> Self {
        let (a, b) = (1.0 / motor_tau_s, 1.0 / rotor_tau_s);
        Self {
            max_speed: max_speed_radps,
            inv_rotor_tau: b,
            half: Decay::over(a, b, 0.5 * dt_s),
            full: Decay::over(a, b, dt_s),
        }
    }

    #[inline(always)]
    fn advance(&self, r: &Rotors, command: &[f64; 4], d: &Decay) -> Rotors {
        let offset: [f64; 4] = core::array::from_fn(|i| r.motor[i] - command[i]);
        Rotors {
            motor: core::array::from_fn(|i| command[i] + offset[i] * d.motor),
            speed: core::array::from_fn(|i| {
                let target = self.max_speed * command[i];
                target + (r.speed[i] - target) * d.rotor + self.max_speed * offset[i] * d.cross
            }),
        }
    }

    /// The state half a step on, command held. `#[inline]` (like [`Self::full_step`]) so that
    /// callers in other crates, the `dynamics` benchmark among them, inline it as the runner
    /// does: called, the benchmark timed a differently compiled step from the runner's.
    #[inline]
    pub fn half_step(&self, r: &Rotors, command: &[f64; 4]) -> Rotors {
        self.advance(r, command, &self.half)
    }

    /// The state a full step on, command held.
    #[inline]
    pub fn full_step(&self, r: &Rotors, command: &[f64; 4]) -> Rotors {
        self.advance(r, command, &self.full)
    }

    /// dΩ_i/dt of the second stage, rad/s².
    #[inline(always)]
    pub fn acceleration(&self, r: &Rotors) -> [f64; 4] {
        core::array::from_fn(|i| (self.max_speed * r.motor[i] - r.speed[i]) * self.inv_rotor_tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_satisfies_the_differential_equations() {
        // Central differences of the half and full step around the half step must match the
        // model's right-hand sides there (away from rest, where the slopes are not near zero).
        let dt = 1e-4;
        let (ta, tb, max) = (0.01, 0.04, 1000.0);
        let fine = MotorModel::new(ta, tb, max, dt);
        let quarter = MotorModel::new(ta, tb, max, 0.5 * dt);
        let start = Rotors {
            motor: [0.1, 0.3, 0.9, 0.5],
            speed: [50.0, 500.0, 100.0, 500.0],
        };
        let cmd = [1.0, 0.3, 0.1, 0.2];
        let mid = fine.half_step(&start, &cmd);
        let end = fine.full_step(&start, &cmd);
        let mid_again = quarter.full_step(&start, &cmd);
        let acc = fine.acceleration(&mid);
        for i in 0..4 {
            assert!((mid.motor[i] - mid_again.motor[i]).abs() < 1e-15);
            assert!((mid.speed[i] - mid_again.speed[i]).abs() < 1e-9);
            // Tolerances: 1e-5 of the largest slopes the stages can have (Ω_max/τ, 1/τ).
            let ds = (end.speed[i] - start.speed[i]) / dt;
            assert!((ds - acc[i]).abs() < 1e-5 * max / tb, "{ds} vs {}", acc[i]);
            let dm = (end.motor[i] - start.motor[i]) / dt;
            assert!(
                (dm - (cmd[i] - mid.motor[i]) / ta).abs() < 1e-5 / ta,
                "{dm}"
            );
        }
    }

    #[test]
    fn equal_time_constants_use_the_limit() {
        let dt = 1e-3;
        let near = MotorModel::new(0.02, 0.02 * (1.0 + 1e-7), 1000.0, dt);
        let same = MotorModel::new(0.02, 0.02, 1000.0, dt);
        let start = Rotors {
            motor: [0.0; 4],
            speed: [0.0; 4],
        };
        let a = near.full_step(&start, &[1.0; 4]);
        let b = same.full_step(&start, &[1.0; 4]);
        assert!(b.speed[0] > 0.0 && (a.speed[0] - b.speed[0]).abs() < 1e-6 * b.speed[0]);
    }
}
