//! Where the beams of a `FLASER` line point. The format stores no field of view, so the
//! benchmark convention is a default and the user can override it.

/// How to lay out `n` equally spaced beams symmetric about body x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FovRule {
    /// 180 degrees: 180/181 beams at 1 degree, 360/361 at 0.5 degree, starting at -90 degrees.
    /// An odd count includes both ends; an even count stops one step short of +90.
    Conventional,
    /// The same layout over a field of view given in radians.
    Radians(f32),
}

impl FovRule {
    /// `(start_angle_rad, increment_rad)` for `n` beams.
    pub fn beam_layout(self, n: usize) -> (f32, f32) {
        let fov = match self {
            FovRule::Conventional => core::f32::consts::PI,
            FovRule::Radians(f) => f,
        };
        let steps = if n % 2 == 1 { n.saturating_sub(1) } else { n }.max(1);
        let inc = fov / steps as f32;
        (-fov / 2.0, inc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(r: f32) -> f32 {
        r.to_degrees()
    }

    #[test]
    fn benchmark_counts_follow_the_convention() {
        for (n, step) in [(180, 1.0), (181, 1.0), (360, 0.5), (361, 0.5)] {
            let (start, inc) = FovRule::Conventional.beam_layout(n);
            assert!((deg(start) + 90.0).abs() < 1e-4, "{n}");
            assert!((deg(inc) - step).abs() < 1e-5, "{n}");
        }
    }

    #[test]
    fn override_spreads_over_the_given_fov() {
        let (start, inc) = FovRule::Radians(240f32.to_radians()).beam_layout(241);
        assert!((deg(start) + 120.0).abs() < 1e-4);
        assert!((deg(inc) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn zero_beams_do_not_divide_by_zero() {
        let (start, inc) = FovRule::Conventional.beam_layout(0);
        assert!(start.is_finite() && inc.is_finite());
    }
}
