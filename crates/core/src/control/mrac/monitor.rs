//! The adaptive element's watchdog: decides when it is misbehaving, so the controller resets its
//! weights and flies on with the baseline (reference model, PD, feed-forward) alone.

use super::config::FallbackConfig;

/// Why the adaptive element was switched off. Reported once, as an event the autopilot's log
/// keeps (worth a STATUSTEXT to the ground station).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FallbackReason {
    /// A weight or the element's output was NaN or infinite.
    NonFinite,
    /// A channel's weights sat on their bound for longer than `max_pinned_s`: the error it is
    /// asked to cancel is beyond the element's authority, or it is diverging.
    WeightBound,
    /// The hedge stayed above `hedge_threshold_m_s2` for longer than `max_hedged_s`: the
    /// vehicle has not been able to fly the commands for that long.
    PersistentHedge,
    /// The MRAC configuration failed [`MracConfig::validate`](super::MracConfig::validate):
    /// the autopilot flies the PID cascade instead (reported at start-up).
    InvalidConfig,
}

/// How long each condition has held without a break.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Monitor {
    pinned_s: [f32; 3],
    hedged_s: f32,
}

impl Monitor {
    /// Accounts for `dt` seconds in which channel k's weights were (`pinned[k]`) or were not on
    /// their bound, with a hedge of magnitude `hedge_m_s2`; the reason to fall back, if any.
    pub fn observe(
        &mut self,
        c: &FallbackConfig,
        finite: bool,
        pinned: [bool; 3],
        hedge_m_s2: f32,
        dt: f32,
    ) -> Option<FallbackReason> {
        if !finite {
            return Some(FallbackReason::NonFinite);
        }
        let mut over_bound = false;
        for (t, p) in self.pinned_s.iter_mut().zip(pinned) {
            *t = if p { *t + dt } else { 0.0 };
            over_bound |= *t > c.max_pinned_s;
        }
        // A NaN hedge counts as saturated.
        self.hedged_s = if hedge_m_s2 <= c.hedge_threshold_m_s2 {
            0.0
        } else {
            self.hedged_s + dt
        };
        if over_bound {
            Some(FallbackReason::WeightBound)
        } else if self.hedged_s > c.max_hedged_s {
            Some(FallbackReason::PersistentHedge)
        } else {
            None
        }
    }

    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_condition_fires_only_after_it_has_held_long_enough() {
        let c = FallbackConfig {
            max_pinned_s: 0.5,
            hedge_threshold_m_s2: 2.0,
            max_hedged_s: 1.0,
        };
        // Binary-exact steps: 32 of them are exactly 0.5 s.
        let dt = 1.0 / 64.0;
        let mut m = Monitor::default();
        assert_eq!(
            m.observe(&c, false, [false; 3], 0.0, dt),
            Some(FallbackReason::NonFinite)
        );
        let pinned_y = [false, true, false];
        for _ in 0..32 {
            assert_eq!(m.observe(&c, true, pinned_y, 0.0, dt), None);
        }
        // A break resets the clock; the 33rd pinned step in a row would have fired.
        assert_eq!(m.observe(&c, true, [false; 3], 0.0, dt), None);
        for _ in 0..32 {
            assert_eq!(m.observe(&c, true, pinned_y, 0.0, dt), None);
        }
        assert_eq!(
            m.observe(&c, true, pinned_y, 0.0, dt),
            Some(FallbackReason::WeightBound)
        );
        m.reset();
        for _ in 0..64 {
            assert_eq!(m.observe(&c, true, [false; 3], 3.0, dt), None);
        }
        assert_eq!(
            m.observe(&c, true, [false; 3], f32::NAN, dt),
            Some(FallbackReason::PersistentHedge)
        );
    }
}
