//! The cascaded loops of seed 002 sec. II.B.3: position -> velocity -> attitude -> rate.
//!
//! "A position control loop generates a velocity command, a velocity control loop generates an
//! attitude command, and an attitude control loop generates servo commands to stabilize the
//! vehicle by controlling the angular rate." Each loop is a [`Pid`] with output limits, so the
//! saturations of Kannan's cascade (seed 002 ref. 12) bound what an outer loop can ask for:
//! speed, tilt, body rate. The innermost rate loop is the rate-damping law of seed 002 eqs. 4-6
//! ([`crate::control::sas`]) with the pilot's deflection replaced by gain x rate setpoint, plus an
//! integral; the collective comes from the vertical loops and is tilt-compensated.
//! Attitude errors are taken on Euler angles, which is adequate within the tilt limit.

use super::inversion;
use super::mixer::Demand;
use super::mrac::{
    Command, FallbackReason, Mrac, MracConfig, MracConfigError, MracError, AUTOPILOT_CENTRES,
};
use super::pid::{Pid, PidError};
use crate::geom::normalize_angle;
use crate::msgs::EstimatedState;

pub use super::cascade_config::CascadeConfig;

/// What the guidance asks of the vertical channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Vertical {
    /// Hold this world height (m) through the height loop.
    Height(f32),
    /// Fly this climb rate (m/s, up positive), bypassing the height loop: landing descends at
    /// a rate, not to a height.
    ClimbRate(f32),
}

/// How a moving horizontal setpoint moves, world frame. The velocity is added to the position
/// loop's output and the acceleration to the velocity loop's, so the setpoint is followed
/// without the lag an error would need to ask for that speed or that change of speed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FeedForward {
    pub velocity_m_s: [f32; 2],
    pub accel_m_s2: [f32; 2],
}

impl FeedForward {
    fn is_finite(&self) -> bool {
        self.velocity_m_s
            .iter()
            .chain(&self.accel_m_s2)
            .all(|v| v.is_finite())
    }
}

/// What the guidance asks of the cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSetpoint {
    /// World (x, y) to hold (m); `None` flies level with no horizontal loops, for when the
    /// horizontal estimate cannot be trusted (estimate-invalid landing).
    pub horizontal_m: Option<[f32; 2]>,
    /// How the horizontal setpoint moves; `None` for a fixed setpoint.
    pub feed_forward: Option<FeedForward>,
    pub vertical: Vertical,
    pub yaw_rad: f32,
}

/// The position loops' output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocitySetpoint {
    /// World horizontal velocity (m/s); `None` means level flight.
    pub horizontal_m_s: Option<[f32; 2]>,
    /// The setpoint's own horizontal acceleration (m/s^2), passed on to the velocity loops.
    pub accel_m_s2: [f32; 2],
    pub climb_m_s: f32,
}

/// Attitude and collective asked of the inner loops.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AttitudeTarget {
    pub roll_rad: f32,
    pub pitch_rad: f32,
    pub yaw_rad: f32,
    pub collective: f32,
    /// Vertical specific force asked for (m/s^2): gravity plus the climb loop's demand. The
    /// collective is this, compensated for the tilt of the moment.
    pub lift_m_s2: f32,
}

/// The state of all twelve loops, and of the MRAC when it flies the outer loops instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascade {
    pub config: CascadeConfig,
    position: [Pid; 3],
    velocity: [Pid; 3],
    /// When set, the MRAC replaces the position and velocity PIDs; the inversion, attitude
    /// and rate loops are the same for both.
    mrac: Option<Mrac<AUTOPILOT_CENTRES>>,
    /// Whether the vehicle was airborne at the last actuation: the MRAC learns only then.
    airborne: bool,
    /// The collective the lift asked for at the estimated tilt before the collective bounds,
    /// for the MRAC's hedge (what the bounds and the mixer then took away is hedged).
    wanted_collective: f32,
    attitude: [Pid; 3],
    rate: [Pid; 3],
    /// The velocity loop's last output, held between runs of the outer loops; `None` makes
    /// the next step run them.
    held: Option<AttitudeTarget>,
    /// Time since the outer loops last ran (s).
    outer_elapsed_s: f32,
    /// The filtered roll and pitch commands (rad) when `command_tau_s` > 0; `None` until the
    /// first outer run, which starts the filter at the command itself.
    filtered_tilt_rad: Option<[f32; 2]>,
}

impl Cascade {
    pub fn new(config: CascadeConfig) -> Self {
        let c = config;
        Self {
            config,
            position: [
                Pid::new(c.position_xy),
                Pid::new(c.position_xy),
                Pid::new(c.position_z),
            ],
            velocity: [
                Pid::new(c.velocity_xy),
                Pid::new(c.velocity_xy),
                Pid::new(c.velocity_z),
            ],
            attitude: [
                Pid::new(c.attitude_rp),
                Pid::new(c.attitude_rp),
                Pid::new(c.attitude_yaw),
            ],
            rate: [
                Pid::new(c.rate_rp),
                Pid::new(c.rate_rp),
                Pid::new(c.rate_yaw),
            ],
            mrac: None,
            airborne: false,
            wanted_collective: 0.0,
            held: None,
            outer_elapsed_s: 0.0,
            filtered_tilt_rad: None,
        }
    }

    /// The cascade with the MRAC flying the outer loops (`--controller mrac`).
    pub fn with_mrac(config: CascadeConfig, mrac: MracConfig) -> Result<Self, MracConfigError> {
        Ok(Self {
            mrac: Some(Mrac::new(mrac)?),
            ..Self::new(config)
        })
    }

    /// The MRAC, when it flies the outer loops.
    pub fn mrac(&self) -> Option<&Mrac<AUTOPILOT_CENTRES>> {
        self.mrac.as_ref()
    }

    /// What the mixer delivered of the last demand, and whether the vehicle is airborne: the
    /// MRAC's hedge and learning use them (the PID loops do not).
    pub fn actuated(&mut self, achieved: &Demand, airborne: bool) {
        self.airborne = airborne;
        if let Some(m) = &mut self.mrac {
            m.actuated(self.wanted_collective, achieved.collective);
        }
    }

    /// Tells the MRAC what its pseudo-control became through the inversion: the model's
    /// acceleration for the commanded tilt and lift, so the tilt limit and the lift floor are
    /// hedged.
    fn note_inversion(&mut self, target: &AttitudeTarget, state: &EstimatedState) {
        let hover = self.config.hover_collective;
        if let Some(m) = &mut self.mrac {
            let (roll, pitch) = (target.roll_rad, target.pitch_rad);
            let collective =
                inversion::collective_for(target.lift_m_s2, roll, pitch, hover, 0.0, f32::INFINITY);
            m.inverted(inversion::acceleration_of(
                roll,
                pitch,
                state.yaw_rad,
                collective,
                hover,
            ));
        }
    }

    /// A fallback of the MRAC's adaptive element since the last call.
    pub fn take_fallback(&mut self) -> Option<FallbackReason> {
        self.mrac.as_mut().and_then(|m| m.take_fallback())
    }

    /// Forgets what the MRAC learned (on disarm: the next flight may carry another load).
    pub fn forget_learning(&mut self) {
        if let Some(m) = &mut self.mrac {
            m.forget();
        }
    }

    /// Forgets all integrals and derivative history (mode changes, touchdown).
    pub fn reset(&mut self) {
        for pid in self
            .position
            .iter_mut()
            .chain(self.velocity.iter_mut())
            .chain(self.attitude.iter_mut())
            .chain(self.rate.iter_mut())
        {
            pid.reset();
        }
        if let Some(m) = &mut self.mrac {
            m.reset();
        }
        self.held = None;
        self.outer_elapsed_s = 0.0;
        self.filtered_tilt_rad = None;
    }

    /// Runs the four loops: setpoint and estimate in, mixer demand out. The position and
    /// velocity loops run once `outer_period_s` has passed (over the time since they last
    /// ran), the attitude and rate loops every call. `integrate` false freezes the integrals
    /// that run (the mixer saturated last step, or the vehicle is on the ground).
    pub fn run(
        &mut self,
        setpoint: &CascadeSetpoint,
        state: &EstimatedState,
        gyro_rad_s: [f32; 3],
        dt: f32,
        integrate: bool,
    ) -> Result<Demand, PidError> {
        let elapsed = self.outer_elapsed_s + dt;
        // Half a step of slack, so rounding in the sum does not skip a period.
        let mut target = match self.held {
            Some(held) if elapsed + 0.5 * dt < self.config.outer_period_s => {
                self.outer_elapsed_s = elapsed;
                held
            }
            _ => {
                let mut target = match self.adaptive_acceleration(setpoint, state, elapsed)? {
                    Some(accel) => {
                        let target = self.invert(accel, setpoint.yaw_rad, state);
                        self.note_inversion(&target, state);
                        target
                    }
                    None => {
                        let velocity_sp = self.velocity_setpoint(setpoint, state, elapsed)?;
                        self.attitude_target(
                            velocity_sp,
                            setpoint.yaw_rad,
                            state,
                            elapsed,
                            integrate,
                        )?
                    }
                };
                self.filter_tilt(&mut target, elapsed);
                self.held = Some(target);
                self.outer_elapsed_s = 0.0;
                target
            }
        };
        target.yaw_rad = setpoint.yaw_rad;
        target.collective = self.collective(target.lift_m_s2, state);
        if self.mrac.is_some() {
            let c = &self.config;
            self.wanted_collective = inversion::collective_for(
                target.lift_m_s2,
                state.roll_rad,
                state.pitch_rad,
                c.hover_collective,
                0.0,
                f32::INFINITY,
            );
        }
        let rate_sp = self.rate_setpoint(&target, state, dt)?;
        self.demand(&target, rate_sp, gyro_rad_s, dt, integrate)
    }

    /// Low-passes the tilt of `target` over `dt` (s) when a command filter is configured.
    fn filter_tilt(&mut self, target: &mut AttitudeTarget, dt: f32) {
        let tau = self.config.command_tau_s;
        if tau <= 0.0 {
            return;
        }
        let command = [target.roll_rad, target.pitch_rad];
        let alpha = dt / (tau + dt);
        let filtered = match self.filtered_tilt_rad {
            Some(f) => [0, 1].map(|i| f[i] + alpha * (command[i] - f[i])),
            None => command,
        };
        self.filtered_tilt_rad = Some(filtered);
        [target.roll_rad, target.pitch_rad] = filtered;
    }

    /// The MRAC's outer loops: its pseudo-control (world acceleration, m/s^2), which goes
    /// through the same inversion as the PID's; `None` when the PID loops fly.
    fn adaptive_acceleration(
        &mut self,
        setpoint: &CascadeSetpoint,
        state: &EstimatedState,
        dt: f32,
    ) -> Result<Option<[f32; 3]>, PidError> {
        let airborne = self.airborne;
        let Some(mrac) = &mut self.mrac else {
            return Ok(None);
        };
        let [x, y] = match (setpoint.horizontal_m, setpoint.feed_forward) {
            (Some([x, y]), None) => [Command::Position(x), Command::Position(y)],
            (Some(p), Some(ff)) => core::array::from_fn(|k| Command::Track {
                position_m: p[k],
                velocity_m_s: ff.velocity_m_s[k],
                accel_m_s2: ff.accel_m_s2[k],
            }),
            (None, _) => [Command::Off; 2],
        };
        let z = match setpoint.vertical {
            Vertical::Height(h) => Command::Position(h),
            Vertical::ClimbRate(rate) => Command::Velocity(rate),
        };
        mrac.step([x, y, z], state, dt, airborne)
            .map_err(|e| match e {
                MracError::NonFinite => PidError::NonFinite,
                MracError::BadDt => PidError::BadDt,
            })
            .map(Some)
    }

    /// Position loop: world velocity setpoint (m/s).
    pub fn velocity_setpoint(
        &mut self,
        setpoint: &CascadeSetpoint,
        state: &EstimatedState,
        dt: f32,
    ) -> Result<VelocitySetpoint, PidError> {
        let mut accel_m_s2 = [0.0; 2];
        let horizontal_m_s = match setpoint.horizontal_m {
            Some(target) => {
                let mut v = [0.0; 2];
                for (axis, out) in v.iter_mut().enumerate() {
                    let x = state.position_m[axis];
                    *out = self.position[axis].update(target[axis], x, 0.0, dt, false)?;
                }
                if let Some(ff) = setpoint.feed_forward {
                    if !ff.is_finite() {
                        return Err(PidError::NonFinite);
                    }
                    let u = ff.velocity_m_s;
                    v = [v[0] + u[0], v[1] + u[1]];
                    accel_m_s2 = ff.accel_m_s2;
                }
                Some(v)
            }
            None => {
                self.position[0].reset();
                self.position[1].reset();
                None
            }
        };
        let climb_m_s = match setpoint.vertical {
            Vertical::ClimbRate(rate) if rate.is_finite() => rate,
            Vertical::ClimbRate(_) => return Err(PidError::NonFinite),
            Vertical::Height(h) => {
                self.position[2].update(h, state.position_m[2], 0.0, dt, false)?
            }
        };
        Ok(VelocitySetpoint {
            horizontal_m_s,
            accel_m_s2,
            climb_m_s,
        })
    }

    /// Velocity loop: acceleration demand turned into tilt and a tilt-compensated collective.
    pub fn attitude_target(
        &mut self,
        velocity_sp: VelocitySetpoint,
        yaw_sp: f32,
        state: &EstimatedState,
        dt: f32,
        integrate: bool,
    ) -> Result<AttitudeTarget, PidError> {
        let mut accel = [0.0; 3];
        match velocity_sp.horizontal_m_s {
            Some(target) => {
                for axis in 0..2 {
                    let v = state.velocity_m_s[axis];
                    let ff = velocity_sp.accel_m_s2[axis];
                    accel[axis] = self.velocity[axis].update(target[axis], v, ff, dt, integrate)?;
                }
            }
            None => {
                self.velocity[0].reset();
                self.velocity[1].reset();
            }
        }
        let vz = state.velocity_m_s[2];
        accel[2] = self.velocity[2].update(velocity_sp.climb_m_s, vz, 0.0, dt, integrate)?;
        Ok(self.invert(accel, yaw_sp, state))
    }

    /// The approximate inversion ([`inversion`]): world acceleration to tilt, lift and the
    /// collective at the estimated tilt.
    fn invert(&self, accel_m_s2: [f32; 3], yaw_sp: f32, state: &EstimatedState) -> AttitudeTarget {
        let tilt = inversion::tilt_for(accel_m_s2, state.yaw_rad, self.config.max_tilt_rad);
        AttitudeTarget {
            roll_rad: tilt.roll_rad,
            pitch_rad: tilt.pitch_rad,
            yaw_rad: yaw_sp,
            collective: self.collective(tilt.lift_m_s2, state),
            lift_m_s2: tilt.lift_m_s2,
        }
    }

    /// The collective that gives `lift_m_s2` of vertical specific force at the estimated tilt.
    fn collective(&self, lift_m_s2: f32, state: &EstimatedState) -> f32 {
        let c = &self.config;
        inversion::collective_for(
            lift_m_s2,
            state.roll_rad,
            state.pitch_rad,
            c.hover_collective,
            c.min_collective,
            c.max_collective,
        )
    }

    /// Attitude loop: body rate setpoint (rad/s); heading error wraps to (-pi, pi].
    pub fn rate_setpoint(
        &mut self,
        target: &AttitudeTarget,
        state: &EstimatedState,
        dt: f32,
    ) -> Result<[f32; 3], PidError> {
        let errors = [
            target.roll_rad - state.roll_rad,
            target.pitch_rad - state.pitch_rad,
            normalize_angle(target.yaw_rad - state.yaw_rad),
        ];
        let mut rates = [0.0; 3];
        for (axis, out) in rates.iter_mut().enumerate() {
            *out = self.attitude[axis].update(errors[axis], 0.0, 0.0, dt, false)?;
        }
        Ok(rates)
    }

    /// Rate loop (seed 002 eqs. 4-6 plus integral): deflections, packed with the collective.
    pub fn demand(
        &mut self,
        target: &AttitudeTarget,
        rate_sp: [f32; 3],
        gyro_rad_s: [f32; 3],
        dt: f32,
        integrate: bool,
    ) -> Result<Demand, PidError> {
        let mut d = [0.0; 3];
        for (axis, out) in d.iter_mut().enumerate() {
            let alpha =
                self.rate[axis].update(rate_sp[axis], gyro_rad_s[axis], 0.0, dt, integrate)?;
            let effectiveness = self.config.effectiveness_rad_s2[axis];
            // Plain comparisons: `is_finite` is several integer operations, three times a step.
            if !(effectiveness > 0.0 && effectiveness < f32::INFINITY) {
                return Err(PidError::NonFinite);
            }
            *out = alpha / effectiveness;
        }
        Ok(Demand {
            collective: target.collective,
            roll: d[0],
            pitch: d[1],
            yaw: d[2],
        })
    }
}

#[path = "cascade_retune.rs"]
mod retune;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::GRAVITY_M_S2;
    use libm::{cosf, sinf};

    fn level_at(position_m: [f32; 3]) -> EstimatedState {
        EstimatedState {
            position_m,
            valid: true,
            ..Default::default()
        }
    }

    fn hold(p: [f32; 3]) -> CascadeSetpoint {
        CascadeSetpoint {
            horizontal_m: Some([p[0], p[1]]),
            feed_forward: None,
            vertical: Vertical::Height(p[2]),
            yaw_rad: 0.0,
        }
    }

    fn level(horizontal_m_s: [f32; 2], climb_m_s: f32) -> VelocitySetpoint {
        VelocitySetpoint {
            horizontal_m_s: Some(horizontal_m_s),
            accel_m_s2: [0.0; 2],
            climb_m_s,
        }
    }

    #[test]
    fn at_the_setpoint_it_asks_for_hover_and_nothing_else() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = level_at([1.0, 2.0, 1.0]);
        let d = c
            .run(&hold([1.0, 2.0, 1.0]), &s, [0.0; 3], 0.002, true)
            .unwrap();
        assert!((d.collective - c.config.hover_collective).abs() < 1e-6);
        assert_eq!((d.roll, d.pitch, d.yaw), (0.0, 0.0, 0.0));
    }

    #[test]
    fn the_command_filter_lags_a_step_in_tilt_and_then_reaches_it() {
        let config = CascadeConfig {
            command_tau_s: 0.1,
            ..CascadeConfig::default()
        };
        let mut raw = Cascade::new(CascadeConfig::default());
        let mut smooth = Cascade::new(config);
        let s = level_at([0.0, 0.0, 1.0]);
        let dt = config.outer_period_s;
        for c in [&mut raw, &mut smooth] {
            c.run(&hold([0.0, 0.0, 1.0]), &s, [0.0; 3], dt, false)
                .unwrap();
            c.run(&hold([0.3, 0.0, 1.0]), &s, [0.0; 3], dt, false)
                .unwrap();
        }
        let pitch = |c: &Cascade| c.held.unwrap().pitch_rad;
        let step = pitch(&raw);
        // One period of a 0.1 s filter: a tenth of the way (dt / (tau + dt) = 1/11).
        assert!(step > 0.0, "{step}");
        assert!((pitch(&smooth) - step / 11.0).abs() < 1e-6 * step.max(1.0));
        for _ in 0..200 {
            smooth
                .run(&hold([0.3, 0.0, 1.0]), &s, [0.0; 3], dt, false)
                .unwrap();
        }
        assert!(
            (pitch(&smooth) - step).abs() < 1e-3 * step,
            "{}",
            pitch(&smooth)
        );
        smooth.reset();
        assert_eq!(smooth.filtered_tilt_rad, None);
    }

    #[test]
    fn a_setpoint_speeding_up_is_flown_at_its_acceleration_with_no_error() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = level_at([0.0, 0.0, 1.0]);
        let sp = CascadeSetpoint {
            feed_forward: Some(FeedForward {
                velocity_m_s: [0.0; 2],
                accel_m_s2: [1.0, 0.0],
            }),
            ..hold([0.0, 0.0, 1.0])
        };
        let v = c.velocity_setpoint(&sp, &s, 0.01).unwrap();
        assert_eq!(v.accel_m_s2, [1.0, 0.0]);
        let t = c.attitude_target(v, 0.0, &s, 0.01, false).unwrap();
        // Thrust tilted forward so that its horizontal share is 1 m/s^2 at 1 g of lift.
        let forward = GRAVITY_M_S2 * libm::tanf(t.pitch_rad);
        assert!((forward - 1.0).abs() < 1e-4, "{t:?}");
        assert!(t.roll_rad.abs() < 1e-6);
        let bad = CascadeSetpoint {
            feed_forward: Some(FeedForward {
                velocity_m_s: [0.0; 2],
                accel_m_s2: [f32::NAN, 0.0],
            }),
            ..sp
        };
        assert_eq!(
            c.velocity_setpoint(&bad, &s, 0.01),
            Err(PidError::NonFinite)
        );
    }

    #[test]
    fn the_climb_integral_may_carry_what_the_collective_bounds_can_lift() {
        let c = CascadeConfig::default().fitted(0.275, [400.0, 400.0, 20.0]);
        let authority = GRAVITY_M_S2 * (0.9 / 0.275 - 1.0);
        assert!((c.climb_authority_m_s2() - authority).abs() < 1e-4);
        assert_eq!(c.velocity_z.integral_limit, c.climb_authority_m_s2());
        // Mass x1.3 with one motor at 80 %: 1.3 / 0.95 - 1 of g more than the model's hover.
        assert!(c.velocity_z.integral_limit > (1.3 / 0.95 - 1.0) * GRAVITY_M_S2);
        assert_eq!(c.hover_collective, 0.275);
        assert_eq!(c.effectiveness_rad_s2, [400.0, 400.0, 20.0]);
    }

    #[test]
    fn target_ahead_pitches_nose_down_and_target_left_rolls_left_side_down() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = level_at([0.0, 0.0, 1.0]);
        let v = c
            .velocity_setpoint(&hold([0.25, 0.0, 1.0]), &s, 0.01)
            .unwrap();
        let kp = c.config.position_xy.kp;
        assert_eq!(v, level([kp * 0.25, 0.0], 0.0));
        let t = c.attitude_target(v, 0.0, &s, 0.01, true).unwrap();
        assert!(t.pitch_rad > 0.0 && t.roll_rad.abs() < 1e-6);
        // Heading 90 degrees: the world +x target is now to the vehicle's right.
        let s_left = EstimatedState {
            yaw_rad: core::f32::consts::FRAC_PI_2,
            ..s
        };
        let t = Cascade::new(CascadeConfig::default())
            .attitude_target(level([0.5, 0.0], 0.0), 0.0, &s_left, 0.01, true)
            .unwrap();
        assert!(t.roll_rad > 0.0 && t.pitch_rad.abs() < 1e-5, "{t:?}");
    }

    #[test]
    fn tilt_and_speed_stay_within_limits_for_a_far_setpoint() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = level_at([0.0, 0.0, 1.0]);
        let v = c
            .velocity_setpoint(&hold([100.0, -100.0, 1.0]), &s, 0.01)
            .unwrap();
        assert_eq!(v, level([1.0, -1.0], 0.0));
        let t = c
            .attitude_target(level([50.0, 50.0], 0.0), 0.0, &s, 0.01, true)
            .unwrap();
        let tilt = libm::acosf(cosf(t.roll_rad) * cosf(t.pitch_rad));
        assert!(tilt <= 0.35 + 1e-3, "{tilt}");
    }

    #[test]
    fn collective_compensates_tilt_and_climb() {
        let mut c = Cascade::new(CascadeConfig::default());
        let tilted = EstimatedState {
            roll_rad: 0.3,
            ..level_at([0.0; 3])
        };
        let t = c
            .attitude_target(level([0.0; 2], 0.0), 0.0, &tilted, 0.01, false)
            .unwrap();
        assert!((t.collective - c.config.hover_collective / cosf(0.3)).abs() < 1e-5);
        let climb = CascadeSetpoint {
            vertical: Vertical::ClimbRate(0.5),
            ..hold([0.0; 3])
        };
        let v = c
            .velocity_setpoint(&climb, &level_at([0.0; 3]), 0.01)
            .unwrap();
        assert_eq!(v.climb_m_s, 0.5);
        let t = c
            .attitude_target(v, 0.0, &level_at([0.0; 3]), 0.01, false)
            .unwrap();
        assert!(t.collective > c.config.hover_collective);
    }

    #[test]
    fn without_a_horizontal_setpoint_it_flies_level_whatever_the_drift() {
        let mut c = Cascade::new(CascadeConfig::default());
        let mut s = level_at([3.0, -2.0, 1.0]);
        s.velocity_m_s = [0.5, 0.5, 0.0];
        let sp = CascadeSetpoint {
            horizontal_m: None,
            feed_forward: None,
            vertical: Vertical::ClimbRate(-0.5),
            yaw_rad: 0.0,
        };
        let v = c.velocity_setpoint(&sp, &s, 0.01).unwrap();
        let t = c.attitude_target(v, 0.0, &s, 0.01, true).unwrap();
        assert_eq!((t.roll_rad, t.pitch_rad), (0.0, 0.0));
        // Descending from rest: less than hover collective.
        assert!(t.collective < c.config.hover_collective);
    }

    #[test]
    fn outer_loops_run_at_their_period_and_hold_their_output_between() {
        let sp = hold([0.0, 0.0, 1.0]);
        let here = level_at([0.0, 0.0, 1.0]);
        let away = level_at([0.5, 0.0, 1.0]);
        let dt = 0.002;
        let mut still = Cascade::new(CascadeConfig::default());
        let mut moved = still;
        let step = |c: &mut Cascade, s: &EstimatedState| c.run(&sp, s, [0.0; 3], dt, true);
        assert_eq!(step(&mut still, &here), step(&mut moved, &here));
        // The position loop of `moved` does not see the displacement until 10 ms have passed.
        for _ in 0..4 {
            assert_eq!(step(&mut still, &here), step(&mut moved, &away));
        }
        let (a, b) = (
            step(&mut still, &here).unwrap(),
            step(&mut moved, &away).unwrap(),
        );
        assert!(b.pitch < a.pitch, "{a:?} {b:?}");
        // After a reset the next step runs them at once.
        moved.reset();
        let mut fresh = Cascade::new(CascadeConfig::default());
        assert_eq!(step(&mut fresh, &away), step(&mut moved, &away));
    }

    #[test]
    fn heading_error_takes_the_short_way_round() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = EstimatedState {
            yaw_rad: 3.0,
            ..level_at([0.0; 3])
        };
        let t = AttitudeTarget {
            yaw_rad: -3.0,
            ..Default::default()
        };
        let r = c.rate_setpoint(&t, &s, 0.01).unwrap();
        // -3 - 3 wraps to +0.283: turn counter-clockwise, not 6 rad clockwise.
        assert!(r[2] > 0.0 && r[2] < 1.0, "{r:?}");
    }

    #[test]
    fn rate_loop_p_term_is_the_sas_law() {
        let config = CascadeConfig::default();
        let mut c = Cascade::new(config);
        let sas = super::super::sas::SasConfig {
            gains_per_rad_s: core::array::from_fn(|i| {
                config.rate_rp.kp / config.effectiveness_rad_s2[i]
            }),
            stick_authority: [0.0; 3],
        };
        let gyro = [0.3, -0.2, 0.0];
        let d = c
            .demand(&AttitudeTarget::default(), [0.0; 3], gyro, 0.01, false)
            .unwrap();
        let damped = super::super::sas::damp(&sas, [0.0; 3], gyro);
        // First step: no derivative history, no integral: exactly eqs. 4-5.
        assert!((d.roll - damped[0]).abs() < 1e-6 && (d.pitch - damped[1]).abs() < 1e-6);
    }

    #[test]
    fn non_finite_state_is_an_error_not_a_nan() {
        let mut c = Cascade::new(CascadeConfig::default());
        let s = level_at([f32::NAN, 0.0, 1.0]);
        assert_eq!(
            c.run(&hold([0.0, 0.0, 1.0]), &s, [0.0; 3], 0.01, true),
            Err(PidError::NonFinite)
        );
    }

    /// A point-mass-with-attitude vehicle: the cascade must bring it from 0.3 m off back to the
    /// setpoint and hold it there (seed 000 Fig. 9: the drift driven to zero).
    #[test]
    fn simple_vehicle_returns_to_the_hold_point() {
        let mut c = Cascade::new(CascadeConfig::default());
        let sp = hold([0.0, 0.0, 1.0]);
        let mut s = level_at([0.3, -0.2, 0.8]);
        let mut rates = [0.0f32; 3];
        let dt = 0.002;
        for _ in 0..5000 {
            let d = c.run(&sp, &s, rates, dt, true).unwrap();
            // The plant the configuration declares: effectiveness x deflection.
            let e = c.config.effectiveness_rad_s2;
            rates[0] += e[0] * d.roll * dt;
            rates[1] += e[1] * d.pitch * dt;
            rates[2] += e[2] * d.yaw * dt;
            s.roll_rad += rates[0] * dt;
            s.pitch_rad += rates[1] * dt;
            s.yaw_rad += rates[2] * dt;
            let thrust = GRAVITY_M_S2 * d.collective / c.config.hover_collective;
            let (cr, sr, cp, sp_) = (
                cosf(s.roll_rad),
                sinf(s.roll_rad),
                cosf(s.pitch_rad),
                sinf(s.pitch_rad),
            );
            let acc = [
                thrust * cr * sp_,
                -thrust * sr,
                thrust * cr * cp - GRAVITY_M_S2,
            ];
            for ((v, p), a) in s.velocity_m_s.iter_mut().zip(&mut s.position_m).zip(acc) {
                *v += a * dt;
                *p += *v * dt;
            }
        }
        let p = s.position_m;
        assert!(
            libm::hypotf(p[0], p[1]) < 0.01 && (p[2] - 1.0).abs() < 0.01,
            "{p:?}"
        );
        assert!(s.roll_rad.abs() < 0.01 && s.pitch_rad.abs() < 0.01);
    }
}
