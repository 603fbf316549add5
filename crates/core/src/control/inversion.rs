//! Approximate dynamic inversion of the translational dynamics (seed 002 eq. 7 and the text after
//! it): the model `f_hat` that turns a tilt and a collective into an acceleration, and its inverse
//! `f_hat^-1`, which turns the acceleration a loop asks for (the pseudo-control `nu`) into the
//! tilt and collective the inner loops fly.
//!
//! The model is a point mass under gravity and one thrust along body z whose size is
//! `g x collective / hover_collective`. It ignores drag, rotor dynamics and any error in mass or
//! motor strength; what it leaves out is the model error `Delta = f - f_hat` that the PID's
//! integrals or the adaptive element of [`crate::control::mrac`] make up. The PID cascade and the
//! MRAC fly through the same inverse, and the MRAC's hedge uses the forward model, so the two
//! agree exactly where nothing saturates.

use crate::msgs::GRAVITY_M_S2;
use libm::{atanf, cosf, sincosf, sqrtf};

/// The attitude and vertical specific force that deliver an acceleration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tilt {
    pub roll_rad: f32,
    pub pitch_rad: f32,
    /// Vertical specific force asked for (m/s^2): gravity plus the vertical acceleration,
    /// never less than 30 % of gravity so the vehicle stays upright.
    pub lift_m_s2: f32,
}

/// The vertical specific force (m/s^2) the inversion asks for a vertical acceleration
/// `accel_z_m_s2`: gravity plus it, never less than 30 % of gravity so the vehicle stays upright.
#[inline(always)]
pub fn lift_for(accel_z_m_s2: f32) -> f32 {
    (GRAVITY_M_S2 + accel_z_m_s2).max(0.3 * GRAVITY_M_S2)
}

/// `f_hat^-1` for the attitude: world acceleration (m/s^2, z up) to roll, pitch and lift at
/// heading `yaw_rad`, the horizontal part scaled down to fit `max_tilt_rad`.
#[inline(always)]
pub fn tilt_for(accel_m_s2: [f32; 3], yaw_rad: f32, max_tilt_rad: f32) -> Tilt {
    let lift = lift_for(accel_m_s2[2]);
    // Horizontal demand rotated into the heading frame, bounded by the tilt limit.
    let (s, co) = sincosf(yaw_rad);
    let mut ax = co * accel_m_s2[0] + s * accel_m_s2[1];
    let mut ay = -s * accel_m_s2[0] + co * accel_m_s2[1];
    let max_h = lift * libm::tanf(max_tilt_rad);
    let h = sqrtf(ax * ax + ay * ay);
    if h > max_h {
        ax *= max_h / h;
        ay *= max_h / h;
    }
    // ZYX Euler, FLU: thrust along body z tilts to (cos(phi) sin(theta), -sin(phi)).
    // cos(pitch) = lift / sqrt(lift^2 + ax^2), so roll needs no cosine of its own.
    Tilt {
        roll_rad: atanf(-ay / sqrtf(lift * lift + ax * ax)),
        pitch_rad: atanf(ax / lift),
        lift_m_s2: lift,
    }
}

/// `f_hat^-1` for the thrust: the collective that gives `lift_m_s2` of vertical specific force at
/// the tilt of the moment, within `[min, max]`. The tilt factor is floored at 0.5 so a large
/// tilt never asks for more than twice the level collective.
#[inline(always)]
pub fn collective_for(
    lift_m_s2: f32,
    roll_rad: f32,
    pitch_rad: f32,
    hover_collective: f32,
    min: f32,
    max: f32,
) -> f32 {
    let tilt = cosf(roll_rad) * cosf(pitch_rad);
    let collective = hover_collective * lift_m_s2 / GRAVITY_M_S2 / tilt.max(0.5);
    collective.clamp(min, max)
}

/// `f_hat`: the world acceleration (m/s^2, z up) the model predicts for this attitude and
/// collective (the mixer's achieved one, for pseudo-control hedging).
pub fn acceleration_of(
    roll_rad: f32,
    pitch_rad: f32,
    yaw_rad: f32,
    collective: f32,
    hover_collective: f32,
) -> [f32; 3] {
    let thrust = GRAVITY_M_S2 * collective / hover_collective;
    let (sr, cr) = sincosf(roll_rad);
    let (sp, cp) = sincosf(pitch_rad);
    let (sy, cy) = sincosf(yaw_rad);
    // Body z in the world for ZYX Euler angles.
    let (hx, hy) = (cr * sp, -sr);
    [
        thrust * (cy * hx - sy * hy),
        thrust * (sy * hx + cy * hy),
        thrust * cr * cp - GRAVITY_M_S2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_model_delivers_what_its_inverse_was_asked_within_the_limits() {
        let hover = 0.35;
        for (accel, yaw) in [
            ([1.0, -0.5, 0.3], 0.0),
            ([-2.0, 1.5, -1.0], 1.2),
            ([0.0, 0.0, 0.0], -2.5),
        ] {
            let t = tilt_for(accel, yaw, 0.6);
            let c = collective_for(t.lift_m_s2, t.roll_rad, t.pitch_rad, hover, 0.0, 1.0);
            let a = acceleration_of(t.roll_rad, t.pitch_rad, yaw, c, hover);
            for k in 0..3 {
                assert!((a[k] - accel[k]).abs() < 1e-4, "{accel:?} -> {a:?}");
            }
        }
        // Beyond the tilt limit the model delivers less than was asked, in the same direction.
        let t = tilt_for([8.0, 0.0, 0.0], 0.0, 0.35);
        let c = collective_for(t.lift_m_s2, t.roll_rad, t.pitch_rad, hover, 0.0, 1.0);
        let a = acceleration_of(t.roll_rad, t.pitch_rad, 0.0, c, hover);
        assert!(
            (a[0] - GRAVITY_M_S2 * libm::tanf(0.35)).abs() < 1e-3,
            "{a:?}"
        );
    }
}
