//! Whether a leg is getting anywhere: the remaining length of the way to its goal must shrink
//! by [`PROGRESS_M`] within [`NO_PROGRESS_S`]. A leg that does not is replanned round the place
//! it stalled at once; if it still makes no progress for another [`NO_PROGRESS_S`], it is given
//! up, so a vehicle that cannot get home lands at most `2 × NO_PROGRESS_S` after its last
//! progress instead of hovering until the battery runs down.

/// Time allowed without progress before the leg is replanned, and again before it is given
/// up, s. Passing a person in a door or sidestepping a mover takes well under this.
pub const NO_PROGRESS_S: f64 = 30.0;
/// Shrinking of the remaining way that counts as progress, m: more than the field's sway
/// between walls, less than a door's width.
pub const PROGRESS_M: f32 = 0.5;

/// What to do about the leg now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Progressing,
    /// No progress for [`NO_PROGRESS_S`]: plan the leg again, avoiding where it stalled.
    Replan,
    /// No progress for [`NO_PROGRESS_S`] after a replan: give the leg up.
    GiveUp,
}

/// The progress of one leg.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressWatch {
    /// The shortest remaining way since the last progress (or replan), m.
    best_m: f32,
    /// When that was, s.
    since_s: f64,
    /// The leg has been replanned since its last progress.
    replanned: bool,
}

impl ProgressWatch {
    /// A leg starting at `t_s` with `remaining_m` to go (not finite: unknown, so any finite
    /// length is progress).
    pub fn new(t_s: f64, remaining_m: f32) -> Self {
        Self {
            best_m: if remaining_m.is_finite() {
                remaining_m
            } else {
                f32::INFINITY
            },
            since_s: t_s,
            replanned: false,
        }
    }

    /// Takes in the remaining way to the goal at `t_s`, m. A non-finite length is no progress.
    pub fn check(&mut self, t_s: f64, remaining_m: f32) -> Verdict {
        if remaining_m.is_finite() && remaining_m <= self.best_m - PROGRESS_M {
            *self = Self::new(t_s, remaining_m);
            return Verdict::Progressing;
        }
        if t_s - self.since_s < NO_PROGRESS_S {
            return Verdict::Progressing;
        }
        if self.replanned {
            return Verdict::GiveUp;
        }
        // The replanned way may be longer: progress is measured from it.
        *self = Self {
            replanned: true,
            ..Self::new(t_s, remaining_m)
        };
        Verdict::Replan
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stuck_leg_is_replanned_then_given_up_within_twice_the_bound() {
        let mut w = ProgressWatch::new(0.0, 16.5);
        let mut verdicts = Vec::new();
        // A revolution every 0.25 s, the way home never shorter than 16.3 m.
        for step in 1..=400 {
            let t = f64::from(step) * 0.25;
            let v = w.check(t, 16.3 + 0.2 * (t as f32).sin());
            if v != Verdict::Progressing {
                verdicts.push((t, v));
            }
        }
        assert_eq!(verdicts[0], (NO_PROGRESS_S, Verdict::Replan));
        assert_eq!(verdicts[1], (2.0 * NO_PROGRESS_S, Verdict::GiveUp));
    }

    #[test]
    fn steady_progress_is_never_stopped_and_progress_after_a_replan_clears_it() {
        let mut w = ProgressWatch::new(0.0, 20.0);
        for step in 1..=400 {
            let t = f64::from(step) * 0.25;
            // 0.05 m/s: slow, but 0.5 m every 10 s.
            assert_eq!(w.check(t, 20.0 - 0.05 * t as f32), Verdict::Progressing);
        }
        let mut w = ProgressWatch::new(0.0, 10.0);
        assert_eq!(w.check(30.0, 10.0), Verdict::Replan);
        assert_eq!(w.check(40.0, 9.4), Verdict::Progressing);
        // Progress after the replan: the next stall is replanned again, not given up.
        assert_eq!(w.check(70.0, 9.4), Verdict::Replan);
        assert_eq!(w.check(100.0, f32::NAN), Verdict::GiveUp);
    }
}
