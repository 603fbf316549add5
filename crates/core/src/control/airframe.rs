//! What the controllers need to know about the vehicle, and the control constants that follow.
//!
//! The rate loop works in angular acceleration and the vertical loop in fractions of hover
//! thrust, so one set of gains flies different quadrotors once these two figures are known:
//! the hover collective and the angular acceleration a unit mixer deflection produces.

use crate::msgs::{FrameKind, GRAVITY_M_S2};

/// A quadrotor's mass properties, geometry and rotors (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Airframe {
    pub frame: FrameKind,
    pub mass_kg: f32,
    /// Principal moments of inertia about body x, y, z.
    pub inertia_kgm2: [f32; 3],
    /// Centre of gravity to rotor hub.
    pub arm_length_m: f32,
    /// Thrust of one rotor at full command.
    pub max_thrust_n: f32,
    /// Rotor drag torque per unit thrust (k_M / k_T of seed 002 eq. 15), metres.
    pub yaw_moment_per_thrust_m: f32,
}

impl Airframe {
    /// Collective (fraction of one rotor's full thrust) that carries the weight when level.
    pub fn hover_collective(&self) -> f32 {
        self.mass_kg * GRAVITY_M_S2 / (4.0 * self.max_thrust_n)
    }

    /// Angular acceleration (rad/s^2) about body x, y, z from a unit mixer deflection: each
    /// contributing rotor's thrust changes by its full thrust times its coefficient (see
    /// [`super::mixer`]), so the torque is the sum of |coefficient| x lever arm x full thrust.
    pub fn effectiveness_rad_s2(&self) -> [f32; 3] {
        let mut lever = [0.0f32; 2];
        for m in self.frame.motors() {
            // Mixer coefficients are +-1 on the rotors off each axis, 0 on the rotors on it.
            lever[0] += if libm::fabsf(m.arm_dir[1]) > 0.1 {
                libm::fabsf(m.arm_dir[1])
            } else {
                0.0
            };
            lever[1] += if libm::fabsf(m.arm_dir[0]) > 0.1 {
                libm::fabsf(m.arm_dir[0])
            } else {
                0.0
            };
        }
        let t = self.max_thrust_n;
        [
            lever[0] * self.arm_length_m * t / self.inertia_kgm2[0],
            lever[1] * self.arm_length_m * t / self.inertia_kgm2[1],
            4.0 * self.yaw_moment_per_thrust_m * t / self.inertia_kgm2[2],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::mixer::{Demand, Mixer};

    fn pelican(frame: FrameKind) -> Airframe {
        Airframe {
            frame,
            mass_kg: 1.0,
            inertia_kgm2: [0.01, 0.01, 0.02],
            arm_length_m: 0.21,
            max_thrust_n: 7.0,
            yaw_moment_per_thrust_m: 0.016,
        }
    }

    #[test]
    fn effectiveness_matches_the_torque_the_mixer_produces() {
        for frame in [FrameKind::X, FrameKind::Plus] {
            let a = pelican(frame);
            let e = a.effectiveness_rad_s2();
            // Roll 0.1 through the mixer, torque from the rotor positions: alpha = tau / I.
            let mixed = Mixer::new(frame).mix(Demand {
                collective: 0.5,
                roll: 0.1,
                pitch: 0.0,
                yaw: 0.0,
            });
            let mut tau_x = 0.0;
            for (m, f) in frame.motors().iter().zip(mixed.thrust_norm) {
                tau_x += m.arm_dir[1] * a.arm_length_m * f * a.max_thrust_n;
            }
            let alpha = tau_x / a.inertia_kgm2[0];
            assert!(
                (alpha - 0.1 * e[0]).abs() < 1e-3 * e[0],
                "{frame:?}: {alpha} vs {}",
                0.1 * e[0]
            );
        }
        // The figures the default cascade was tuned with.
        let e = pelican(FrameKind::X).effectiveness_rad_s2();
        assert!(
            (e[0] - 415.8).abs() < 0.5 && (e[2] - 22.4).abs() < 0.05,
            "{e:?}"
        );
        assert!((pelican(FrameKind::X).hover_collective() - 0.350).abs() < 1e-3);
    }
}
