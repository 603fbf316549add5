//! Model-reference adaptive control of the translational loops (seed 002 eqs. 7-12, Fig. 6).
//!
//! It takes the place of the PID cascade's position and velocity loops: position (or climb-rate)
//! commands in, the world acceleration the vehicle should fly (the pseudo-control `nu`) out.
//! The cascade's approximate inversion ([`crate::control::inversion`]) turns `nu` into tilt and
//! collective, and the attitude and rate loops fly that exactly as they do for the PID.
//!
//! Per world axis (x, y, z), each outer step:
//! 1. hedge ([`hedge`]): what the inversion's limits and the motors cut from the last command;
//! 2. reference model ([`reference`], eq. 8): `x_rm` moves on over the step just flown at that
//!    step's `nu_crm - nu_h`, then gives this step's `nu_crm = f_rm(x_rm, r)`;
//! 3. tracking error `e = x_rm - x` (position and velocity), PD `nu_pd = kp e_p + kd e_v`;
//! 4. adaptive element ([`rbf`], eq. 11) `nu_ad = W^T sigma(v, nu_crm)`;
//! 5. `nu = nu_crm + nu_pd + c_d v_rm - nu_ad` (eq. 9, with the horizontal drag fed forward on
//!    the model's velocity), and eq. 12 trains `W` on `e^T P B`, with
//!    e-modification, the weights projected onto a ball;
//! 6. the watchdog ([`monitor`]) switches the adaptive element off, resetting its weights, when
//!    it misbehaves; the baseline (reference model, PD, feed-forward) flies on and the reason is
//!    reported once, for the autopilot's event log;
//! 7. the horizontal `nu` is scaled by the lift the vertical channel had to add ([`lift`]): a
//!    thrust-scale error learned vertically is then no error horizontally either.
//!
//! State is a few hundred bytes plus 36 bytes per RBF centre `C` (weights and centre), with no
//! heap; `C` is a const generic so an embedded build sizes it with `core::mem::size_of`.

pub mod config;
pub mod hedge;
pub mod lift;
pub mod monitor;
pub mod rbf;
pub mod reference;

pub use config::{
    AdaptiveConfig, FallbackConfig, MracConfig, MracConfigError, PdGains, ReferenceConfig,
};
pub use monitor::FallbackReason;
pub use reference::Command;

use crate::msgs::EstimatedState;
use monitor::Monitor;
use rbf::{Basis, Rates, RbfNetwork};
use reference::ReferenceChannel;

/// The number of RBF centres the autopilot flies with: enough to cover the six normalised
/// inputs coarsely (the bias and linear terms carry the bulk of a thrust or mass error).
pub const AUTOPILOT_CENTRES: usize = 16;

/// Why a step was refused; the controller's state is left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MracError {
    /// Position, velocity or attitude estimate, or a command, was NaN or infinite.
    NonFinite,
    /// `dt` was not a positive finite number.
    BadDt,
}

/// The MRAC's state: reference model, network, hedge and watchdog.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mrac<const C: usize> {
    pub config: MracConfig,
    reference: [ReferenceChannel; 3],
    /// False until the first step after a reset puts the reference model where the vehicle is.
    started: bool,
    network: RbfNetwork<C>,
    /// `P B` per channel, `P` solving `A^T P + P A = -I` for `A = [0 1; -kp -kd]`.
    pb: [[f32; 2]; 3],
    /// The last pseudo-control commanded (m/s^2), for the hedge; `None` after a reset.
    last_command: Option<[f32; 3]>,
    /// The factor [`lift`] put on its horizontal part.
    last_lift_scale: f32,
    /// The reference model's own acceleration at the last step (m/s^2): the model moves on
    /// by it, less the hedge, once that step's outcome is known.
    last_model_accel: [f32; 3],
    /// The model's horizontal jerk, low-passed (m/s^3), for the lead.
    jerk: [f32; 2],
    /// What the inversion made of the last command (m/s^2, see [`hedge`]).
    deliverable: Option<[f32; 3]>,
    /// Delivered over wanted collective at the last actuation.
    thrust_ratio: f32,
    hedge: [f32; 3],
    monitor: Monitor,
    /// False once the watchdog has switched the adaptive element off.
    adaptive_on: bool,
    /// Why it was switched off.
    fallback: Option<FallbackReason>,
    /// A fallback not yet collected by [`Mrac::take_fallback`].
    unreported: Option<FallbackReason>,
}

/// `P B` for the error dynamics of one channel (see [`Mrac`]'s `pb`): with `Q = I`,
/// `p12 = 1 / (2 kp)`, `p22 = (1 + kp) / (2 kp kd)`.
fn lyapunov_pb(pd: &PdGains) -> [f32; 2] {
    let (kp, kd) = (pd.kp_per_s2, pd.kd_per_s);
    [1.0 / (2.0 * kp), (1.0 + kp) / (2.0 * kp * kd)]
}

impl<const C: usize> Mrac<C> {
    /// A controller with zero weights, after checking `config`.
    pub fn new(config: MracConfig) -> Result<Self, MracConfigError> {
        config.validate()?;
        Ok(Self {
            config,
            reference: [ReferenceChannel::default(); 3],
            started: false,
            network: RbfNetwork::new(),
            pb: [
                lyapunov_pb(&config.pd_xy),
                lyapunov_pb(&config.pd_xy),
                lyapunov_pb(&config.pd_z),
            ],
            last_command: None,
            last_lift_scale: 1.0,
            last_model_accel: [0.0; 3],
            jerk: [0.0; 2],
            deliverable: None,
            thrust_ratio: 1.0,
            hedge: [0.0; 3],
            monitor: Monitor::default(),
            adaptive_on: config.adaptive.enabled,
            fallback: None,
            unreported: None,
        })
    }

    /// New gains and bounds, keeping the reference model, the weights and the watchdog's state
    /// (a lower weight bound is applied by the next learning step's projection). Switching the adaptive
    /// element off takes at once; switching it on waits for the next [`Mrac::forget`] (disarm).
    pub fn retune(&mut self, config: MracConfig) -> Result<(), MracConfigError> {
        config.validate()?;
        self.pb = [
            lyapunov_pb(&config.pd_xy),
            lyapunov_pb(&config.pd_xy),
            lyapunov_pb(&config.pd_z),
        ];
        self.adaptive_on &= config.adaptive.enabled;
        self.config = config;
        Ok(())
    }

    /// Restarts the reference model from the vehicle's state at the next step and forgets the
    /// hedge (mode changes). The learned weights stay: the model error they hold (a heavier
    /// vehicle, a weak motor) does not change with the mode.
    pub fn reset(&mut self) {
        self.started = false;
        self.last_command = None;
        self.last_lift_scale = 1.0;
        self.last_model_accel = [0.0; 3];
        self.jerk = [0.0; 2];
        self.deliverable = None;
        self.thrust_ratio = 1.0;
        self.hedge = [0.0; 3];
        self.monitor.reset();
    }

    /// Forgets what was learned and re-enables the adaptive element (on disarm: the next
    /// flight may carry another payload).
    pub fn forget(&mut self) {
        self.reset();
        self.network.reset_weights();
        self.adaptive_on = self.config.adaptive.enabled;
        self.fallback = None;
        self.unreported = None;
    }

    /// What the inversion made of the last pseudo-control: the model's acceleration for the
    /// tilt and lift it commanded (m/s^2). Feeds the next hedge.
    pub fn inverted(&mut self, deliverable_m_s2: [f32; 3]) {
        self.deliverable = Some(deliverable_m_s2);
    }

    /// The collective the inner loop wanted and what the collective bounds and the mixer
    /// delivered of it. Feeds the next hedge.
    pub fn actuated(&mut self, wanted_collective: f32, achieved_collective: f32) {
        self.thrust_ratio = if wanted_collective > 0.0 && achieved_collective.is_finite() {
            achieved_collective / wanted_collective
        } else {
            1.0
        };
    }

    /// Norm of all adaptive weights (m/s^2 per unit basis).
    pub fn weight_norm(&self) -> f32 {
        self.network.norm()
    }

    /// The hedge of the last step, m/s^2 per world axis.
    pub fn hedge_m_s2(&self) -> [f32; 3] {
        self.hedge
    }

    /// True while the adaptive element is flying (configured on and not fallen back).
    pub fn adaptive_active(&self) -> bool {
        self.adaptive_on
    }

    /// Why the adaptive element was switched off, if it was.
    pub fn fallback(&self) -> Option<FallbackReason> {
        self.fallback
    }

    /// A fallback that happened since the last call (each is returned once).
    pub fn take_fallback(&mut self) -> Option<FallbackReason> {
        self.unreported.take()
    }

    /// The reference model's position and velocity per world axis.
    pub fn reference(&self) -> [(f32, f32); 3] {
        self.reference.map(|r| (r.position_m, r.velocity_m_s))
    }

    /// One outer step: commands per world axis and the estimate in, the pseudo-control (world
    /// acceleration, m/s^2, z up, gravity not included; horizontally in the inversion's units,
    /// see [`lift`]) out. `adapt` false freezes the weights (on the ground, where the
    /// ground and not the controller holds the vehicle).
    pub fn step(
        &mut self,
        commands: [Command; 3],
        state: &EstimatedState,
        dt: f32,
        adapt: bool,
    ) -> Result<[f32; 3], MracError> {
        if !(dt > 0.0 && dt < f32::INFINITY) {
            return Err(MracError::BadDt);
        }
        let finite = |v: f32| v.is_finite();
        let command_finite = commands.iter().all(|c| match c {
            Command::Position(v) | Command::Velocity(v) => v.is_finite(),
            Command::Track {
                position_m,
                velocity_m_s,
                accel_m_s2,
            } => position_m.is_finite() && velocity_m_s.is_finite() && accel_m_s2.is_finite(),
            Command::Off => true,
        });
        if !(state.position_m.iter().all(|v| finite(*v))
            && state.velocity_m_s.iter().all(|v| finite(*v))
            && [state.roll_rad, state.pitch_rad, state.yaw_rad]
                .iter()
                .all(|v| finite(*v))
            && command_finite)
        {
            return Err(MracError::NonFinite);
        }
        if !self.started {
            for k in 0..3 {
                self.reference[k] = ReferenceChannel {
                    position_m: state.position_m[k],
                    velocity_m_s: state.velocity_m_s[k],
                };
            }
            self.started = true;
        }
        let on = commands.map(|c| c != Command::Off);

        // 1. Hedge: what the last command did not deliver.
        self.hedge = match (self.last_command, self.deliverable) {
            (Some(nu), Some(d)) => hedge::hedge(nu, d, self.thrust_ratio, self.last_lift_scale),
            _ => [0.0; 3],
        };

        // 2-3. The reference model moves on over the step just flown, hedged; its output now
        // and the tracking error.
        let mut nu_crm = [0.0; 3];
        let mut e = [[0.0f32; 2]; 3];
        for k in 0..3 {
            let rc = if k < 2 {
                &self.config.reference_xy
            } else {
                &self.config.reference_z
            };
            if on[k] {
                if self.last_command.is_some() {
                    self.reference[k].advance(self.last_model_accel[k] - self.hedge[k], dt);
                }
                nu_crm[k] = self.reference[k].acceleration(rc, commands[k]);
                e[k] = [
                    self.reference[k].position_m - state.position_m[k],
                    self.reference[k].velocity_m_s - state.velocity_m_s[k],
                ];
            } else {
                // No control: the model waits where the vehicle is.
                self.reference[k] = ReferenceChannel {
                    position_m: state.position_m[k],
                    velocity_m_s: state.velocity_m_s[k],
                };
                self.hedge[k] = 0.0;
            }
        }

        // 4. Adaptive element.
        let a = &self.config.adaptive;
        let basis = Basis::new(
            &self.network,
            state.velocity_m_s,
            nu_crm,
            a.velocity_scale_m_s,
            a.accel_scale_m_s2,
            a.rbf_width,
        );
        let nu_ad = if self.adaptive_on {
            self.network.output(&basis)
        } else {
            [0.0; 3]
        };

        // 5. Pseudo-control (eq. 9) and learning (eq. 12).
        let mut baseline = [0.0; 3];
        for k in (0..3).filter(|k| on[*k]) {
            let pd = if k < 2 {
                &self.config.pd_xy
            } else {
                &self.config.pd_z
            };
            baseline[k] = nu_crm[k] + pd.kp_per_s2 * e[k][0] + pd.kd_per_s * e[k][1];
            if k < 2 {
                let c = &self.config;
                if self.last_command.is_some() {
                    let raw = (nu_crm[k] - self.last_model_accel[k]) / dt;
                    self.jerk[k] += (raw - self.jerk[k]) * dt / (c.lead_filter_s + dt);
                }
                baseline[k] += c.drag_feed_forward_per_s * self.reference[k].velocity_m_s
                    + c.lead_s * self.jerk[k];
            }
        }
        let mut nu: [f32; 3] =
            core::array::from_fn(|k| if on[k] { baseline[k] - nu_ad[k] } else { 0.0 });
        let mut verdict = None;
        if self.adaptive_on && adapt {
            let rates = Rates {
                bias_learning_rate: a.bias_learning_rate,
                learning_rate: a.learning_rate,
                e_modification: a.e_modification,
                dt,
            };
            let mut pinned = [false; 3];
            for k in (0..3).filter(|k| on[*k]) {
                let e_pb = e[k][0] * self.pb[k][0] + e[k][1] * self.pb[k][1];
                let e_norm = libm::hypotf(e[k][0], e[k][1]);
                self.network.learn(k, &basis, e_pb, e_norm, rates);
                pinned[k] = self.network.project(k, a.weight_bound);
            }
            let finite = self.network.norm().is_finite() && nu.iter().all(|v| v.is_finite());
            let hedge_norm = libm::sqrtf(self.hedge.iter().map(|h| h * h).sum());
            verdict = self
                .monitor
                .observe(&self.config.fallback, finite, pinned, hedge_norm, dt);
        } else if !nu.iter().all(|v| v.is_finite()) {
            // Only the adaptive part can be non-finite: the inputs were checked.
            verdict = Some(FallbackReason::NonFinite);
        }
        if let Some(reason) = verdict {
            self.fall_back(reason);
            nu = baseline;
        }

        // 7. The vertical channel's thrust-scale error on the horizontal demands.
        let scale = if on[2] {
            lift::horizontal_scale(baseline[2], nu[2])
        } else {
            1.0
        };
        nu[0] *= scale;
        nu[1] *= scale;

        self.last_model_accel = nu_crm;
        self.last_command = Some(nu);
        self.last_lift_scale = scale;
        Ok(nu)
    }

    /// Switches the adaptive element off and resets its weights; the reason is reported once.
    fn fall_back(&mut self, reason: FallbackReason) {
        self.network.reset_weights();
        self.adaptive_on = false;
        self.fallback = Some(reason);
        self.unreported = Some(reason);
        self.monitor.reset();
    }
}

#[cfg(test)]
mod tests;
