//! The cascade's gains and limits, and the two tunings Plumbline ships: one place to read what
//! every loop may ask for.

use super::pid::PidConfig;
use crate::msgs::GRAVITY_M_S2;

/// Gains and limits of the whole cascade. Defaults suit the simulator's "pelican" vehicle (1 kg,
/// 0.21 m arms, 7 N rotors); for another vehicle set `effectiveness_rad_s2` and
/// `hover_collective` from its parameters and the loop gains carry over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeConfig {
    /// Horizontal position error (m) -> velocity setpoint (m/s), per world axis.
    pub position_xy: PidConfig,
    /// Height error (m) -> climb-rate setpoint (m/s).
    pub position_z: PidConfig,
    /// Horizontal velocity error (m/s) -> acceleration (m/s^2), per world axis.
    pub velocity_xy: PidConfig,
    /// Climb-rate error (m/s) -> vertical acceleration (m/s^2).
    pub velocity_z: PidConfig,
    /// Roll or pitch error (rad) -> body rate setpoint (rad/s).
    pub attitude_rp: PidConfig,
    /// Heading error (rad) -> yaw rate setpoint (rad/s).
    pub attitude_yaw: PidConfig,
    /// Roll or pitch rate error (rad/s) -> angular acceleration (rad/s^2); `kp` is the rate
    /// damping of seed 002 eqs. 4-5 expressed per unit of angular acceleration.
    pub rate_rp: PidConfig,
    /// Yaw rate error (rad/s) -> angular acceleration (rad/s^2) (seed 002 eq. 6).
    pub rate_yaw: PidConfig,
    /// Angular acceleration (rad/s^2) one unit of mixer deflection produces about body x, y, z:
    /// rotor thrust x lever arm / inertia (yaw: rotor drag-torque ratio x thrust / inertia).
    pub effectiveness_rad_s2: [f32; 3],
    /// Largest tilt the velocity loop may command (rad).
    pub max_tilt_rad: f32,
    /// Collective that holds the vehicle up when level (fraction of full thrust per motor).
    pub hover_collective: f32,
    /// Collective bounds, so a descent never cuts the motors and a climb leaves torque margin.
    pub min_collective: f32,
    pub max_collective: f32,
    /// The position and velocity loops run at most this often (s); the attitude and rate loops
    /// run every step. Loops of a few rad/s bandwidth gain nothing from the IMU's 500 Hz, and
    /// running them there was half of the controller's cost.
    pub outer_period_s: f32,
    /// Time constant of a first-order low-pass on the roll and pitch the velocity loop asks
    /// for (s); 0 passes them unfiltered. Smoother tilt commands mean gentler motor speed
    /// changes, at the price of a slower answer to a push (seed 000 sec. 5.3's trade-off).
    pub command_tau_s: f32,
}

impl CascadeConfig {
    /// The vertical acceleration above hover (m/s^2) that the collective bounds leave when
    /// level: `g (max_collective / hover_collective - 1)`.
    pub fn climb_authority_m_s2(&self) -> f32 {
        GRAVITY_M_S2 * (self.max_collective / self.hover_collective - 1.0)
    }

    /// These gains on a vehicle with this hover collective and control effectiveness. The
    /// climb integral, which carries whatever the hover collective gets wrong (a heavier
    /// vehicle, a weak motor), may then carry as much as the collective can lift: a fixed
    /// bound below that would leave a vehicle the motors can fly unable to climb to its
    /// height.
    pub fn fitted(self, hover_collective: f32, effectiveness_rad_s2: [f32; 3]) -> Self {
        let mut c = Self {
            hover_collective,
            effectiveness_rad_s2,
            ..self
        };
        c.velocity_z.integral_limit = c.climb_authority_m_s2();
        c
    }

    /// The "soft" tuning of the energy comparison (seed 000 sec. 5.3: smoother control may spend
    /// less energy): slower position and velocity loops, same inner loops.
    pub fn soft() -> Self {
        let d = Self::default();
        Self {
            position_xy: PidConfig {
                kp: 1.0,
                ..d.position_xy
            },
            velocity_xy: PidConfig {
                kp: 3.0,
                ki: 0.3,
                ..d.velocity_xy
            },
            attitude_rp: PidConfig {
                kp: 7.0,
                ..d.attitude_rp
            },
            ..d
        }
    }
}

impl Default for CascadeConfig {
    /// The "aggressive" tuning, chosen over 8-20 seeds of the simulator's XV-11 hold with a
    /// 2 N push (crates/sim/tests/closed_loop.rs); stiffer loops (position 2, velocity 5,
    /// attitude 10, rate 40) oscillate on the lidar's noise there.
    fn default() -> Self {
        let c = Self {
            position_xy: PidConfig::p(1.5, 1.0),
            position_z: PidConfig::p(1.5, 0.8),
            velocity_xy: PidConfig {
                kp: 4.0,
                // 0.5 winds up during a 1 s, 2 N push and swings the vehicle into the wall
                // behind it on some seeds (4 of 20); 0.2 had none.
                ki: 0.2,
                kd: 0.0,
                integral_limit: 1.5,
                output_limit: 4.0,
                derivative_tau_s: 0.0,
            },
            velocity_z: PidConfig {
                kp: 4.0,
                ki: 1.0,
                kd: 0.0,
                // Set by `fitted` from the collective bounds.
                integral_limit: 0.0,
                output_limit: 5.0,
                derivative_tau_s: 0.0,
            },
            attitude_rp: PidConfig::p(8.0, 4.0),
            attitude_yaw: PidConfig::p(2.5, 1.5),
            rate_rp: PidConfig {
                kp: 30.0,
                ki: 30.0,
                kd: 0.4,
                integral_limit: 20.0,
                output_limit: 160.0,
                derivative_tau_s: 0.01,
            },
            rate_yaw: PidConfig {
                kp: 8.0,
                ki: 4.0,
                kd: 0.0,
                integral_limit: 2.0,
                output_limit: 10.0,
                derivative_tau_s: 0.0,
            },
            // 4 rotors x 7 N x 0.21 m / sqrt(2) / 0.01 kg m^2; yaw 4 x 0.016 m x 7 N / 0.02.
            effectiveness_rad_s2: [416.0, 416.0, 22.4],
            max_tilt_rad: 0.35,
            hover_collective: 0.35,
            min_collective: 0.05,
            max_collective: 0.9,
            outer_period_s: 0.01,
            command_tau_s: 0.0,
        };
        c.fitted(c.hover_collective, c.effectiveness_rad_s2)
    }
}
