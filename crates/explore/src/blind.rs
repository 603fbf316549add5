//! When to stop exploring because the position is no longer seen.
//!
//! Down a blank corridor a short-range lidar measures the position across the corridor and
//! nothing along it: the flight part's estimate carries the axis on the IMU and the drag
//! reading alone, and its one-sigma along the axis grows about linearly, at the speed's
//! one-sigma (some 0.3-0.5 m/s in a draughty building). The flight part flies on such an
//! estimate until that one-sigma reaches its degraded bound, and then lands where it is,
//! wherever that is. Exploring on into the blank spends that bound going further from where
//! the axis was last seen, and the way back to it costs as much again.
//!
//! So exploring ends while the way back still fits: the one-sigma grows at a rate `g`, it
//! is `s` now, and if it grew linearly from about zero since the features were lost the
//! way back (as long as the way in) adds another `s`, and stopping and turning round adds
//! `g` times [`BlindBudget::turn_s`]. Exploring ends once `2 s + g turn_s` reaches the bound.
//! The way home over the map then goes back the way the vehicle came, toward the features
//! it last saw.

/// Tracks the flight part's horizontal position one-sigma and says when the way back from a
/// blank stretch no longer fits in the degraded bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlindBudget {
    /// The flight part's degraded position bound, m: one-sigma along the unobserved axis at
    /// which it stops flying and lands.
    pub bound_m: f32,
    /// Time to stop and turn back, s: the one-sigma's growth over it is kept in hand.
    pub turn_s: f32,
    /// The previous revolution's time and one-sigma, for the growth rate.
    last: Option<(f64, f32)>,
}

impl BlindBudget {
    pub fn new(bound_m: f32, turn_s: f32) -> Self {
        Self {
            bound_m,
            turn_s,
            last: None,
        }
    }

    /// Takes the flight part's per-axis position one-sigmas (world x, y) at `t_s` and says
    /// whether the way back still fits (`true`: explore on). The larger principal one-sigma
    /// is bounded by the root of their sum of squares, which is what is judged: exact along
    /// a corridor, whose across one-sigma is centimetres, at any heading.
    pub fn update(&mut self, t_s: f64, position_std_m: [f32; 2]) -> bool {
        let [sx, sy] = position_std_m;
        let s = (sx * sx + sy * sy).sqrt();
        let growth = match self.last {
            Some((t0, s0)) if t_s > t0 => ((s - s0) / (t_s - t0) as f32).max(0.0),
            _ => 0.0,
        };
        self.last = Some((t_s, s));
        // A non-finite one-sigma is no way back either.
        2.0 * s + growth * self.turn_s < self.bound_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-sigma of `rate` m/s from `start_s` on, sampled at the XV-11's 4 Hz; the time
    /// exploring ends.
    fn ends_at(rate: f32, start_s: f64) -> Option<f64> {
        let mut b = BlindBudget::new(3.0, 2.0);
        (0..400).map(|i| f64::from(i) * 0.25).find(|&t| {
            let s = (rate * (t - start_s).max(0.0) as f32).max(0.03);
            !b.update(t, [s, 0.02])
        })
    }

    #[test]
    fn a_blank_stretch_ends_exploring_while_the_way_back_still_fits() {
        // 0.3 m/s of growth from 10 s: 2 s + 0.6 reaches 3 m at s = 1.2 m, 4 s in.
        let t = ends_at(0.3, 10.0).expect("never ended");
        assert!((13.75..=14.0).contains(&t), "ended at {t} s");
        // Flying back as long as in, plus the turn, stays within the 3 m bound (to within
        // the growth of the revolution it is judged on).
        let s_back = 0.3 * ((t - 10.0) * 2.0 + 2.0) as f32;
        assert!(s_back <= 3.0 + 0.3 * 0.25, "{s_back}");
    }

    #[test]
    fn a_faster_growth_ends_exploring_sooner_and_a_seen_position_never() {
        let slow = ends_at(0.3, 10.0).unwrap();
        let fast = ends_at(0.5, 10.0).unwrap();
        assert!(fast < slow, "{fast} vs {slow}");
        assert_eq!(ends_at(0.0, 0.0), None);
    }

    #[test]
    fn the_along_axis_is_judged_at_any_heading() {
        let mut b = BlindBudget::new(3.0, 0.0);
        let along = 1.45_f32;
        let (c, s) = (0.6_f32.cos(), 0.6_f32.sin());
        // Across one-sigma 0.03 m: per-axis one-sigmas of a corridor at 0.6 rad.
        let per_axis = |a: f32| [(a * c).hypot(0.03 * s), (a * s).hypot(0.03 * c)];
        assert!(b.update(0.0, per_axis(along)));
        assert!(!b.update(0.25, per_axis(1.51)));
        assert!(!b.update(0.5, [f32::NAN, 0.0]));
    }
}
