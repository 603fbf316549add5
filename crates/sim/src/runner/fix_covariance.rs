//! The covariance the exploring companion sends with each SLAM pose: the SLAM's measured error
//! in the map, plus what the pose's scan match observed, and a direction the match did not
//! observe (a featureless corridor's axis) marked as such, so the autopilot corrects the
//! position across it only.

use plumbline_slam::Observed;

/// One-sigma uncertainty of each SLAM pose beyond what its scan match observed: the SLAM's
/// measured errors on the simulated surveys (a few centimetres, about half a degree), which
/// come from the keyframes' drift in the map more than from the match.
const FIX_STD_M: f32 = 0.1;
const FIX_STD_RAD: f32 = 0.03;
/// Variance sent along a direction the scan match did not observe (a corridor's axis), m²: far
/// beyond the autopilot's bound, so it fuses the fix across that direction only, and moderate
/// enough that the covariance stays positive definite in f32 at any heading.
const UNOBSERVED_FIX_VARIANCE_M2: f32 = 100.0;

/// The covariance sent with a SLAM pose: the SLAM's measured error, plus what the scan match
/// observed; along a direction the match did not observe, [`UNOBSERVED_FIX_VARIANCE_M2`]
/// instead of the match's (unbounded) variance.
pub fn fix_covariance(observed: Option<&Observed>) -> [[f32; 3]; 3] {
    let (s2, r2) = (FIX_STD_M * FIX_STD_M, FIX_STD_RAD * FIX_STD_RAD);
    let mut c = [[s2, 0.0, 0.0], [0.0, s2, 0.0], [0.0, 0.0, r2]];
    let Some(o) = observed else {
        return c;
    };
    match o.degenerate_direction {
        Some(d) => {
            // d[i] * d[j] first: the same bits for (i, j) and (j, i), an exactly symmetric sum.
            let d = [d.x, d.y];
            for (i, row) in c.iter_mut().take(2).enumerate() {
                for (j, v) in row.iter_mut().take(2).enumerate() {
                    *v += UNOBSERVED_FIX_VARIANCE_M2 * (d[i] * d[j]);
                }
            }
            c[2][2] += o.covariance[2][2];
        }
        None => {
            for (row, m) in c.iter_mut().zip(&o.covariance) {
                for (v, m) in row.iter_mut().zip(m) {
                    *v += m;
                }
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_core::geom::Vec2;

    fn variance_along(c: &[[f32; 3]; 3], u: Vec2) -> f32 {
        u.x * u.x * c[0][0] + 2.0 * u.x * u.y * c[0][1] + u.y * u.y * c[1][1]
    }

    #[test]
    fn an_unmatched_pose_gets_the_measured_error_alone() {
        let (s2, r2) = (FIX_STD_M * FIX_STD_M, FIX_STD_RAD * FIX_STD_RAD);
        assert_eq!(
            fix_covariance(None),
            [[s2, 0.0, 0.0], [0.0, s2, 0.0], [0.0, 0.0, r2]]
        );
    }

    #[test]
    fn a_matched_pose_adds_what_the_match_observed() {
        let observed = Observed {
            covariance: [[4e-4, 1e-4, 2e-5], [1e-4, 9e-4, -3e-5], [2e-5, -3e-5, 1e-5]],
            degenerate_direction: None,
        };
        let c = fix_covariance(Some(&observed));
        let s2 = FIX_STD_M * FIX_STD_M;
        assert!((c[0][0] - (s2 + 4e-4)).abs() < 1e-7 && (c[1][1] - (s2 + 9e-4)).abs() < 1e-7);
        assert_eq!(
            (c[0][1], c[1][0], c[0][2], c[2][1]),
            (1e-4, 1e-4, 2e-5, -3e-5)
        );
    }

    #[test]
    fn a_degenerate_direction_is_sent_as_unobserved_along_it_only() {
        let along = Vec2::new(0.6, -0.8);
        let observed = Observed {
            // What the matcher reports along a corridor: a huge variance along its axis.
            covariance: [[3.6e3, -4.8e3, 0.0], [-4.8e3, 6.4e3, 0.0], [0.0, 0.0, 1e-6]],
            degenerate_direction: Some(along),
        };
        let c = fix_covariance(Some(&observed));
        let s2 = FIX_STD_M * FIX_STD_M;
        assert!((variance_along(&c, along) - (s2 + UNOBSERVED_FIX_VARIANCE_M2)).abs() < 1e-3);
        assert!(
            (variance_along(&c, along.perp()) - s2).abs() < 1e-5,
            "{c:?}"
        );
        assert_eq!(c[0][1], c[1][0]);
        assert!((c[2][2] - (FIX_STD_RAD * FIX_STD_RAD + 1e-6)).abs() < 1e-9);
    }
}
