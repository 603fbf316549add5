//! The thrust-scale error the vertical channel has learned, applied to the horizontal ones.
//!
//! The inversion tilts the thrust so that its horizontal share is `nu_h / (g + nu_z)` of the
//! lift it asks for, assuming the lift it asks for is the lift the vehicle gets. Under a
//! thrust-scale error (a heavier vehicle, a weak motor, a sagging battery) it is not: the
//! vertical adaptive element raises `nu_z` until the vehicle holds its height, and the vertical
//! specific force actually delivered is `g + nu_z` less that correction, i.e. `g` plus the
//! baseline's vertical demand. The inversion then tilts too little, by exactly the ratio of the
//! two lifts, and every horizontal demand (feed-forward of the path's acceleration, the PD,
//! the drag feed-forward) is delivered short by it. A horizontal adaptive element can learn
//! that only as many separate terms, each from the small error it leaves, and not at all for
//! demands its inputs do not show (the PD's share). One thrust acts along body z for all three
//! axes, so the vertical channel's ratio is applied to the horizontal demands instead.

use crate::control::inversion::lift_for;

/// The thrust scale errors the ratio may stand for: from half to twice the model's lift
/// (a vehicle at twice its configured mass, or half). Outside this the vertical element is
/// answering something other than a thrust error (a transient, a vertical push), and a larger
/// horizontal gain would only amplify it.
const SCALE_RANGE: (f32, f32) = (0.5, 2.0);

/// The factor on the horizontal pseudo-control for a vertical pseudo-control `commanded_z_m_s2`
/// (with the adaptive element's correction) of which `wanted_z_m_s2` is the baseline's
/// (without it): the lift asked of the inversion over the lift the vehicle gets. Exactly 1
/// when the adaptive element adds nothing vertically.
pub fn horizontal_scale(wanted_z_m_s2: f32, commanded_z_m_s2: f32) -> f32 {
    (lift_for(commanded_z_m_s2) / lift_for(wanted_z_m_s2)).clamp(SCALE_RANGE.0, SCALE_RANGE.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::GRAVITY_M_S2;

    #[test]
    fn the_ratio_of_the_lifts_within_its_range() {
        assert_eq!(horizontal_scale(0.7, 0.7), 1.0);
        // Mass x1.3: the vertical element asks 0.3 g more to hover.
        let s = horizontal_scale(0.0, 0.3 * GRAVITY_M_S2);
        assert!((s - 1.3).abs() < 1e-6, "{s}");
        assert_eq!(horizontal_scale(0.0, 3.0 * GRAVITY_M_S2), 2.0);
        assert_eq!(horizontal_scale(0.0, -GRAVITY_M_S2), 0.5);
    }
}
