//! Pseudo-control hedging (seed 002 Fig. 6; Johnson and Calise, its refs. 14 and 17): the part
//! of the commanded pseudo-control the vehicle could not be given, which is taken out of the
//! reference model so that neither the tracking error nor the adaptive element sees it.
//!
//! `nu_h = nu_cmd - f_hat(x, delta_achieved)`, where `delta_achieved` is the tilt the inversion
//! commanded (less than asked when the tilt limit or the lift floor bites) with the thrust the
//! motors delivered (less than asked when the collective bounds or the mixer's saturation cut
//! it). Both sides use the same model, so a model error does not show here: it stays in the
//! tracking error, where the adaptive element is meant to find it.
//!
//! The attitude loop's lag behind the commanded tilt is not hedged: hedged, it feeds the
//! vehicle's own motion back into the reference model, which then trails the vehicle instead of
//! leading it, and in the simulator's square track that extra lag set up a 1 Hz pitch
//! oscillation (baseline alone, seed 2: a wall strike at 17 s; unhedged lag: none).

use crate::msgs::GRAVITY_M_S2;

/// The hedge (m/s^2 per world axis) of `commanded_m_s2`, given what the inversion made of it
/// (`deliverable_m_s2`: the model's acceleration for the commanded tilt and lift) and the share
/// of the wanted thrust the motors delivered (`thrust_ratio`, 1 when nothing saturated).
/// `lift_scale` is the factor the horizontal command was given for the thrust-scale error
/// ([`super::lift`]): the horizontal hedge is divided by it, so that it is in the reference
/// model's units (what the vehicle was expected to fly), not the inversion's.
pub fn hedge(
    commanded_m_s2: [f32; 3],
    deliverable_m_s2: [f32; 3],
    thrust_ratio: f32,
    lift_scale: f32,
) -> [f32; 3] {
    // Specific force scales with thrust; gravity does not.
    let mut delivered = deliverable_m_s2;
    delivered[2] += GRAVITY_M_S2;
    core::array::from_fn(|k| {
        let (g, scale) = if k == 2 {
            (GRAVITY_M_S2, 1.0)
        } else {
            (0.0, lift_scale)
        };
        (commanded_m_s2[k] - (thrust_ratio * delivered[k] - g)) / scale
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_what_was_not_delivered_is_hedged() {
        let h = hedge([1.0, -0.5, 0.3], [1.0, -0.5, 0.3], 1.0, 1.0);
        assert!(h.iter().all(|x| x.abs() < 1e-6), "{h:?}");
        // The tilt limit cut 5 m/s^2 forward to 3.6.
        let h = hedge([5.0, 0.0, 0.0], [3.6, 0.0, 0.0], 1.0, 1.0);
        assert!(
            (h[0] - 1.4).abs() < 1e-6 && h[1] == 0.0 && h[2] == 0.0,
            "{h:?}"
        );
        // The motors gave 90 % of the thrust for hover: a tenth of g short vertically.
        let h = hedge([0.0; 3], [0.0; 3], 0.9, 1.0);
        assert!((h[2] - 0.1 * GRAVITY_M_S2).abs() < 1e-5, "{h:?}");
    }
}
