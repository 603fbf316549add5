//! What the autopilot is configured with: the frame, the estimator, the controller and its
//! gains, the supervisor, the mission and the landing, each part beside the code it configures.

use super::mission::MissionConfig;
use super::supervisor::SupervisorConfig;
use crate::control::airframe::Airframe;
use crate::control::cascade::CascadeConfig;
use crate::control::mrac::MracConfig;
use crate::control::sas::SasConfig;
use crate::estimate::estimator::EstimatorConfig;
use crate::msgs::FrameKind;

/// Everything the autopilot can be configured with; defaults are for the nominal 1 kg,
/// 0.17 m-arm X quadrotor with a 3S pack.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AutopilotConfig {
    pub frame: FrameKind,
    pub estimator: EstimatorConfig,
    /// Which law flies the position and velocity loops of the cascade.
    pub controller: ControllerKind,
    pub cascade: CascadeConfig,
    /// Used when `controller` is [`ControllerKind::Mrac`].
    pub mrac: MracConfig,
    pub sas: SasConfig,
    pub supervisor: SupervisorConfig,
    pub landing: LandingConfig,
    pub mission: MissionConfig,
}

impl AutopilotConfig {
    /// Defaults with the frame, hover collective and control effectiveness of `airframe`.
    pub fn for_airframe(airframe: &Airframe) -> Self {
        let mut c = Self {
            frame: airframe.frame,
            ..Self::default()
        };
        c.cascade = c
            .cascade
            .fitted(airframe.hover_collective(), airframe.effectiveness_rad_s2());
        c
    }
}

/// The law that turns position commands into the acceleration the cascade's inversion flies:
/// the only part of the loop that differs between the two.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ControllerKind {
    /// Position and velocity PIDs (seed 000 Fig. 8-9).
    #[default]
    Pid,
    /// Model-reference adaptive control with an RBF network and pseudo-control hedging
    /// (seed 002 eqs. 7-12).
    Mrac,
}

/// Descent rates and the on-ground test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandingConfig {
    /// Normal descent (m/s).
    pub descent_m_s: f32,
    /// Descent when the battery is critical or the lidar is lost (m/s): the IMU-only estimate
    /// a lidar-lost landing flies on strays roughly with the square of the time (0.05 m after
    /// 1 s, 0.20 m after 3 s, 0.52 m after 5 s, mean of 20 simulated seeds), so that landing is
    /// kept short.
    pub urgent_descent_m_s: f32,
    /// Below this estimated height (m) the vehicle counts as on the ground: integrators freeze,
    /// since ground contact, not the controller, is holding it.
    pub ground_height_m: f32,
    /// Longest step accepted (s); longer or non-positive steps are faults.
    pub max_dt_s: f32,
    /// Collective below this fraction of hover counts as "low thrust" for touchdown detection
    /// (a descent at the configured rates never asks for so little).
    pub low_thrust_fraction: f32,
}

impl Default for LandingConfig {
    fn default() -> Self {
        Self {
            descent_m_s: 0.5,
            urgent_descent_m_s: 1.0,
            ground_height_m: 0.05,
            max_dt_s: 0.1,
            low_thrust_fraction: 0.6,
        }
    }
}
