//! The covariance the exploring companion sends with each SLAM pose: the SLAM's measured error
//! in the map, and a direction its scan match did not observe (a featureless corridor's axis)
//! marked as such, so the autopilot corrects the position across it only.

use plumbline_core::geom::Vec2;

/// One-sigma uncertainty of each SLAM pose: the SLAM's measured errors on the simulated surveys
/// (a few centimetres, about half a degree), which come from the keyframes' drift in the map.
/// What a scan match observes is far tighter (a few millimetres, hundredths of a degree): where
/// the match sees both directions its own covariance would change only the last bits of these,
/// so it is not added.
const FIX_STD_M: f32 = 0.1;
const FIX_STD_RAD: f32 = 0.03;

/// Variance added along a direction the scan match did not observe (a corridor's axis), m²:
/// far beyond the autopilot's bound, so it fuses the fix across that direction only, and
/// moderate enough that the covariance stays positive definite in f32 at any heading.
const UNOBSERVED_FIX_VARIANCE_M2: f32 = 100.0;

/// The covariance sent with a SLAM pose whose scan match could not see along `degenerate` (a
/// unit direction in the map frame), if anywhere.
pub fn fix_covariance(degenerate: Option<Vec2>) -> [[f32; 3]; 3] {
    let (s2, r2) = (FIX_STD_M * FIX_STD_M, FIX_STD_RAD * FIX_STD_RAD);
    let mut c = [[s2, 0.0, 0.0], [0.0, s2, 0.0], [0.0, 0.0, r2]];
    if let Some(d) = degenerate {
        // d[i] * d[j] first: the same bits for (i, j) and (j, i), an exactly symmetric sum.
        let d = [d.x, d.y];
        for (i, row) in c.iter_mut().take(2).enumerate() {
            for (j, v) in row.iter_mut().take(2).enumerate() {
                *v += UNOBSERVED_FIX_VARIANCE_M2 * (d[i] * d[j]);
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn variance_along(c: &[[f32; 3]; 3], u: Vec2) -> f32 {
        u.x * u.x * c[0][0] + 2.0 * u.x * u.y * c[0][1] + u.y * u.y * c[1][1]
    }

    #[test]
    fn a_pose_seen_in_every_direction_gets_the_measured_error() {
        let (s2, r2) = (FIX_STD_M * FIX_STD_M, FIX_STD_RAD * FIX_STD_RAD);
        assert_eq!(
            fix_covariance(None),
            [[s2, 0.0, 0.0], [0.0, s2, 0.0], [0.0, 0.0, r2]]
        );
    }

    #[test]
    fn a_degenerate_direction_is_sent_as_unobserved_along_it_only() {
        let along = Vec2::new(0.6, -0.8);
        let c = fix_covariance(Some(along));
        let s2 = FIX_STD_M * FIX_STD_M;
        assert!((variance_along(&c, along) - (s2 + UNOBSERVED_FIX_VARIANCE_M2)).abs() < 1e-3);
        assert!(
            (variance_along(&c, along.perp()) - s2).abs() < 1e-5,
            "{c:?}"
        );
        assert_eq!(c[0][1], c[1][0]);
        assert_eq!(c[2][2], FIX_STD_RAD * FIX_STD_RAD);
    }
}
