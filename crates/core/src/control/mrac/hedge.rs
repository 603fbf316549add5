//! Pseudo-control hedging (seed 002 Fig. 6; Johnson and Calise, its refs. 14 and 17): the part
//! of the commanded pseudo-control the vehicle could not deliver, which is taken out of the
//! reference model so that neither the tracking error nor the adaptive element sees it.
//!
//! `nu_h = nu_cmd - f_hat(x, delta_achieved)`: the acceleration commanded minus what the
//! approximate model predicts from what was actually flown: the estimated attitude (which lags
//! or stops short of the commanded one when the tilt limit, the body-rate limits or the torque
//! saturation of the mixer bite) and the collective the mixer achieved (less than asked when
//! the motors saturate). Both sides use the same model, so a model error does not show here:
//! it stays in the tracking error, where the adaptive element is meant to find it.

use crate::control::inversion::acceleration_of;
use crate::msgs::EstimatedState;

/// The hedge (m/s^2 per world axis) for a command `commanded_m_s2` flown as `state` with the
/// mixer's `achieved_collective`.
pub fn hedge(
    commanded_m_s2: [f32; 3],
    state: &EstimatedState,
    achieved_collective: f32,
    hover_collective: f32,
) -> [f32; 3] {
    let delivered = acceleration_of(
        state.roll_rad,
        state.pitch_rad,
        state.yaw_rad,
        achieved_collective,
        hover_collective,
    );
    core::array::from_fn(|k| commanded_m_s2[k] - delivered[k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::GRAVITY_M_S2;

    #[test]
    fn nothing_is_hedged_when_the_command_was_flown_and_a_shortfall_is() {
        let hover = 0.4;
        let level = EstimatedState::default();
        assert_eq!(hedge([0.0; 3], &level, hover, hover), [0.0; 3]);
        // Climb at 2 m/s^2 asked, but the motors saturated at the hover collective.
        let h = hedge([0.0, 0.0, 2.0], &level, hover, hover);
        assert!((h[2] - 2.0).abs() < 1e-6, "{h:?}");
        // 1 m/s^2 forward asked; the vehicle is still level (the attitude loop lags).
        let h = hedge([1.0, 0.0, 0.0], &level, hover, hover);
        assert_eq!(h, [1.0, 0.0, 0.0]);
        // Once pitched to atan(1/g) it delivers it.
        let pitched = EstimatedState {
            pitch_rad: libm::atanf(1.0 / GRAVITY_M_S2),
            ..level
        };
        let c = hover / libm::cosf(pitched.pitch_rad);
        let h = hedge([1.0, 0.0, 0.0], &pitched, c, hover);
        assert!(h.iter().all(|x| x.abs() < 1e-5), "{h:?}");
    }
}
