//! Rate-damping stability augmentation, seed 002 eqs. 4-6.
//!
//! A quadrotor left alone drifts into growing angular rates; subtracting a multiple of the
//! measured rate from each stick deflection gives the pilot (or the manual mode) a vehicle that
//! comes to rest when the sticks are centred:
//!
//! `delta_phi = delta_phi_p - K_p p`, `delta_theta = delta_theta_p - K_q q`,
//! `delta_psi = delta_psi_p - K_r r` (seed 002 eqs. 4, 5, 6).
//!
//! The automatic rate loop ([`crate::control::cascade`]) is the same law with the pilot's
//! deflection replaced by the rate setpoint times the gain, plus an integral.

/// Rate-damping gains `K_p, K_q, K_r` of seed 002 eqs. 4-6, in normalised deflection per rad/s
/// (a deflection of 1 is a full-thrust difference on one motor; see [`crate::control::mixer`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SasConfig {
    pub gains_per_rad_s: [f32; 3],
    /// Full stick deflection, in normalised deflection units, for roll/pitch and yaw.
    pub stick_authority: [f32; 3],
}

impl Default for SasConfig {
    /// Gains for the simulator's "pelican" (a unit deflection gives about 416 rad/s^2 in roll
    /// and pitch, 22 rad/s^2 in yaw): about 25 rad/s of damping bandwidth on roll and pitch and
    /// 9 rad/s on yaw.
    fn default() -> Self {
        Self {
            gains_per_rad_s: [0.06, 0.06, 0.4],
            stick_authority: [0.1, 0.1, 0.4],
        }
    }
}

/// Seed 002 eqs. 4-6: sticks in [-1, 1] (roll, pitch, yaw, signed as on a Mode-2 radio: see
/// [`crate::msgs::PilotInput`]) and FLU body rates in, FLU roll, pitch and yaw deflections out.
/// Non-finite inputs are treated as zero so the output is finite.
///
/// Roll right is a positive rotation about FLU x (the right side goes down, the thrust tilts to
/// -y, the vehicle slides right) and pitch forward a positive rotation about FLU y (nose down,
/// the thrust tilts to +x), so both sticks pass through unchanged. Yaw right turns clockwise
/// seen from above, which is a negative rotation about FLU z (z up): the yaw stick is negated.
pub fn damp(config: &SasConfig, sticks_norm: [f32; 3], gyro_rad_s: [f32; 3]) -> [f32; 3] {
    let to_flu = [1.0, 1.0, -1.0];
    let mut out = [0.0; 3];
    for i in 0..3 {
        let stick = finite_or_zero(sticks_norm[i]).clamp(-1.0, 1.0);
        let pilot = to_flu[i] * stick * config.stick_authority[i];
        out[i] = pilot - config.gains_per_rad_s[i] * finite_or_zero(gyro_rad_s[i]);
    }
    out
}

fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centred_sticks_oppose_the_rate_with_the_gain() {
        let c = SasConfig {
            gains_per_rad_s: [0.1, 0.2, 0.3],
            stick_authority: [1.0; 3],
        };
        let d = damp(&c, [0.0; 3], [1.0, -2.0, 0.5]);
        assert_eq!(d, [-0.1, 0.4, -0.15]);
    }

    #[test]
    fn stick_maps_to_flu_deflection_and_is_clamped() {
        let c = SasConfig {
            gains_per_rad_s: [0.0; 3],
            stick_authority: [0.25, 0.25, 0.2],
        };
        // Roll right is positive FLU roll, pitch forward positive FLU pitch (nose down), yaw
        // right (clockwise from above) negative FLU yaw.
        assert_eq!(damp(&c, [1.0, 1.0, 1.0], [0.0; 3]), [0.25, 0.25, -0.2]);
        assert_eq!(damp(&c, [5.0, -5.0, -5.0], [0.0; 3]), [0.25, -0.25, 0.2]);
    }

    #[test]
    fn damped_rigid_body_comes_to_rest() {
        // I w' = k * delta with delta = -K w: the rate decays as exp(-k K t / I).
        let c = SasConfig::default();
        let (mut w, dt) = (2.0f32, 0.001);
        for _ in 0..1000 {
            let d = damp(&c, [0.0; 3], [w, 0.0, 0.0]);
            w += 416.0 * d[0] * dt;
        }
        assert!(w.abs() < 1e-3, "{w}");
    }

    #[test]
    fn non_finite_inputs_give_finite_output() {
        let d = damp(
            &SasConfig::default(),
            [f32::NAN, 0.0, 0.0],
            [f32::INFINITY, 0.0, 0.0],
        );
        assert!(d.iter().all(|x| x.is_finite()));
    }
}
