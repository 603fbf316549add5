//! A single-axis PID: anti-windup, derivative on measurement, output limits.
//!
//! The derivative acts on the measurement, not the error, so a setpoint step gives no derivative
//! kick (seed 000 Fig. 9 steps the hold setpoint when the pilot lets go of the sticks). The
//! integral is clamped and stops integrating while the output is saturated in the direction the
//! error pushes, so a long saturation does not leave a windup to unwind afterwards.

/// Gains and limits of one PID. Units depend on the loop (documented where it is configured).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidConfig {
    /// Output per unit of error.
    pub kp: f32,
    /// Output per unit of error-second.
    pub ki: f32,
    /// Output per unit of measurement rate (applied with a minus sign: derivative on measurement).
    pub kd: f32,
    /// Bound on the magnitude of the integral term's contribution to the output.
    pub integral_limit: f32,
    /// Symmetric output bound: the output lies in [-output_limit, output_limit].
    pub output_limit: f32,
    /// Time constant of the first-order low-pass on the derivative, seconds (0 = unfiltered).
    pub derivative_tau_s: f32,
}

impl PidConfig {
    /// A proportional-only controller with an output bound.
    pub const fn p(kp: f32, output_limit: f32) -> Self {
        Self {
            kp,
            ki: 0.0,
            kd: 0.0,
            integral_limit: 0.0,
            output_limit,
            derivative_tau_s: 0.0,
        }
    }
}

/// Why a PID refused to step; its state is left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PidError {
    /// Setpoint, measurement or feed-forward was NaN or infinite.
    NonFinite,
    /// `dt` was not a positive finite number.
    BadDt,
}

/// One PID's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pid {
    pub config: PidConfig,
    /// The integral term's current contribution to the output (already multiplied by `ki`).
    integral: f32,
    /// Previous measurement, for the derivative; `None` right after a reset.
    last_measurement: Option<f32>,
    /// Low-passed measurement rate.
    rate: f32,
}

impl Pid {
    pub const fn new(config: PidConfig) -> Self {
        Self {
            config,
            integral: 0.0,
            last_measurement: None,
            rate: 0.0,
        }
    }

    /// Forgets the integral and derivative history (on mode changes and touchdown).
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.last_measurement = None;
        self.rate = 0.0;
    }

    /// New gains and limits, keeping the loop's state. The integral is kept as the output
    /// contribution it has built up (it is stored already multiplied by `ki`), so a new `ki`
    /// changes how fast it grows from here, not where it is; a lower `integral_limit` clips it
    /// at once.
    pub fn retune(&mut self, config: PidConfig) {
        self.config = config;
        let limit = config.integral_limit;
        self.integral = self.integral.clamp(-limit, limit);
    }

    /// The integral term's contribution to the output.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// One step. `feedforward` is added before limiting; `integrate` false freezes the integral
    /// (the caller knows of saturation downstream, e.g. a mixer at its limits). Inlined: a
    /// dozen run each step, most with constant arguments the caller's copy can fold away.
    #[inline(always)]
    pub fn update(
        &mut self,
        setpoint: f32,
        measurement: f32,
        feedforward: f32,
        dt: f32,
        integrate: bool,
    ) -> Result<f32, PidError> {
        // Plain comparisons and x * 0 (0 when finite, NaN when not): this runs a dozen times a
        // step, and `is_finite` costs several integer operations per value (the compiler turns
        // `dt < INFINITY` into those too). The error is NaN or infinite when either of its
        // operands is (or when their difference overflows f32, which is refused as well).
        if !(dt > 0.0 && dt * 0.0 == 0.0) {
            return Err(PidError::BadDt);
        }
        let error = setpoint - measurement;
        if error * 0.0 + feedforward * 0.0 != 0.0 {
            return Err(PidError::NonFinite);
        }
        let c = &self.config;
        // Most loops of the cascade have no derivative or no integral; they skip that arithmetic
        // (with kd zero the measurement rate starts from rest if kd is set later).
        if c.kd != 0.0 {
            if let Some(last) = self.last_measurement {
                let raw = (measurement - last) / dt;
                let alpha = if c.derivative_tau_s > 0.0 {
                    dt / (c.derivative_tau_s + dt)
                } else {
                    1.0
                };
                self.rate += alpha * (raw - self.rate);
            }
        }
        self.last_measurement = Some(measurement);

        let unlimited_without_i = feedforward + c.kp * error - c.kd * self.rate;
        let trial = unlimited_without_i + self.integral;
        // Conditional integration: integrate unless the output is already at a bound and the
        // error would push it further past that bound.
        let pushing_out =
            (trial >= c.output_limit && error > 0.0) || (trial <= -c.output_limit && error < 0.0);
        if integrate && !pushing_out && c.ki != 0.0 {
            let i = self.integral + c.ki * error * dt;
            self.integral = i.clamp(-c.integral_limit, c.integral_limit);
        }
        Ok((unlimited_without_i + self.integral).clamp(-c.output_limit, c.output_limit))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> PidConfig {
        PidConfig {
            kp: 2.0,
            ki: 1.0,
            kd: 0.5,
            integral_limit: 0.3,
            output_limit: 1.0,
            derivative_tau_s: 0.0,
        }
    }

    #[test]
    fn retuning_keeps_the_integral_and_clips_it_to_a_lower_limit() {
        let mut pid = Pid::new(cfg());
        for _ in 0..20 {
            pid.update(0.1, 0.0, 0.0, 0.1, true).unwrap();
        }
        let built = pid.integral();
        assert!(built > 0.15, "{built}");
        // A new ki leaves the contribution where it is: the output does not jump.
        pid.retune(PidConfig { ki: 5.0, ..cfg() });
        assert_eq!(pid.integral(), built);
        pid.retune(PidConfig {
            integral_limit: 0.1,
            ..cfg()
        });
        assert_eq!(pid.integral(), 0.1);
    }

    #[test]
    fn proportional_step_is_kp_times_error_and_has_no_derivative_kick() {
        let mut pid = Pid::new(PidConfig { ki: 0.0, ..cfg() });
        pid.update(0.0, 0.0, 0.0, 0.01, true).unwrap();
        // Setpoint step of 0.25: only the P term answers; the measurement did not move.
        let u = pid.update(0.25, 0.0, 0.0, 0.01, true).unwrap();
        assert!((u - 0.5).abs() < 1e-6, "{u}");
    }

    #[test]
    fn derivative_opposes_measurement_motion() {
        let mut pid = Pid::new(PidConfig {
            kp: 0.0,
            ki: 0.0,
            ..cfg()
        });
        pid.update(0.0, 0.0, 0.0, 0.1, true).unwrap();
        let u = pid.update(0.0, 0.1, 0.0, 0.1, true).unwrap();
        // Measurement rate 1 /s, kd 0.5: output -0.5.
        assert!((u + 0.5).abs() < 1e-5, "{u}");
    }

    #[test]
    fn integral_of_constant_error_ramps_at_ki_times_error() {
        let mut pid = Pid::new(PidConfig {
            kp: 0.0,
            kd: 0.0,
            integral_limit: 10.0,
            ..cfg()
        });
        let mut u = 0.0;
        for _ in 0..50 {
            u = pid.update(0.1, 0.0, 0.0, 0.01, true).unwrap();
        }
        // 0.5 s at error 0.1, ki 1: 0.05.
        assert!((u - 0.05).abs() < 1e-5, "{u}");
    }

    #[test]
    fn integral_stays_bounded_and_unwinds_at_once_after_long_saturation() {
        let mut pid = Pid::new(cfg());
        for _ in 0..10_000 {
            let u = pid.update(10.0, 0.0, 0.0, 0.01, true).unwrap();
            assert!(u <= 1.0);
        }
        assert!(pid.integral() <= 0.3 + 1e-6);
        // Saturated in the positive direction, the integral stopped growing early.
        assert!(pid.integral() < 0.05, "integral {}", pid.integral());
        // Error reverses: the output leaves the bound in one step instead of after a windup.
        let u = pid.update(0.0, 0.2, 0.0, 0.01, true).unwrap();
        assert!(u < 0.0, "{u}");
    }

    #[test]
    fn output_is_limited_and_feedforward_is_added() {
        let mut pid = Pid::new(PidConfig::p(1.0, 0.4));
        assert_eq!(pid.update(5.0, 0.0, 0.0, 0.01, true), Ok(0.4));
        assert_eq!(pid.update(0.0, 5.0, 0.0, 0.01, true), Ok(-0.4));
        let u = pid.update(0.1, 0.0, 0.2, 0.01, true).unwrap();
        assert!((u - 0.3).abs() < 1e-6);
    }

    #[test]
    fn frozen_integral_does_not_move() {
        let mut pid = Pid::new(cfg());
        pid.update(0.1, 0.0, 0.0, 0.01, true).unwrap();
        let before = pid.integral();
        pid.update(0.1, 0.0, 0.0, 0.01, false).unwrap();
        assert_eq!(pid.integral(), before);
    }

    #[test]
    fn closed_loop_first_order_plant_settles_without_steady_state_error() {
        // Plant x' = u - 0.5 (a constant disturbance): integral action must remove the offset.
        let mut pid = Pid::new(PidConfig {
            kd: 0.0,
            integral_limit: 1.0,
            ..cfg()
        });
        let (mut x, dt) = (0.0f32, 0.01);
        for _ in 0..2000 {
            let u = pid.update(1.0, x, 0.0, dt, true).unwrap();
            x += (u - 0.5) * dt;
        }
        assert!((x - 1.0).abs() < 1e-3, "{x}");
    }

    #[test]
    fn bad_inputs_are_refused_and_leave_state_alone() {
        let mut pid = Pid::new(cfg());
        pid.update(0.1, 0.0, 0.0, 0.01, true).unwrap();
        let snapshot = pid;
        assert_eq!(
            pid.update(f32::NAN, 0.0, 0.0, 0.01, true),
            Err(PidError::NonFinite)
        );
        assert_eq!(
            pid.update(0.0, f32::INFINITY, 0.0, 0.01, true),
            Err(PidError::NonFinite)
        );
        assert_eq!(pid.update(0.0, 0.0, 0.0, 0.0, true), Err(PidError::BadDt));
        assert_eq!(
            pid.update(0.0, 0.0, 0.0, f32::NAN, true),
            Err(PidError::BadDt)
        );
        assert_eq!(
            pid.update(0.0, 0.0, 0.0, f32::INFINITY, true),
            Err(PidError::BadDt)
        );
        assert_eq!(
            pid.update(0.0, 0.0, f32::NEG_INFINITY, 0.01, true),
            Err(PidError::NonFinite)
        );
        assert_eq!(pid, snapshot);
    }
}
