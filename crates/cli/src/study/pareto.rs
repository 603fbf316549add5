//! The energy study's verdict, apart from any flying: which settings no other beats on both
//! energy and hold error (the Pareto front), and whether one saves the energy the question asks
//! for without giving up more hold accuracy than it allows.

/// One setting's mean figures over its seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// RMS hold error, m.
    pub error_m: f64,
    /// Battery energy per minute of flight, Wh/min.
    pub energy_wh_min: f64,
}

impl Point {
    /// No worse on both figures and better on one.
    fn dominates(&self, other: &Point) -> bool {
        self.error_m <= other.error_m
            && self.energy_wh_min <= other.energy_wh_min
            && (self.error_m < other.error_m || self.energy_wh_min < other.energy_wh_min)
    }
}

/// Indices of the points no other point dominates, by increasing hold error. Points with a
/// non-finite figure (a crashed setting) are never on the front.
pub fn front(points: &[Point]) -> Vec<usize> {
    let finite = |p: &Point| p.error_m.is_finite() && p.energy_wh_min.is_finite();
    let mut on: Vec<usize> = (0..points.len())
        .filter(|&i| finite(&points[i]))
        .filter(|&i| !points.iter().any(|q| finite(q) && q.dominates(&points[i])))
        .collect();
    on.sort_by(|&a, &b| points[a].error_m.total_cmp(&points[b].error_m));
    on
}

/// The question put to the data: a setting within `error_slack` (0.1: 10 %) of the default's
/// hold error on at least `saving` (0.1: 10 %) less energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// The setting using least energy within the error slack, if any beats the default.
    pub best_within_slack: Option<usize>,
    /// Its energy saving against the default (0.1: 10 %); 0 when none beats the default.
    pub saving_within_slack: f64,
    /// The largest saving of any setting, whatever its hold error.
    pub largest_saving: f64,
    /// Whether `best_within_slack` saves at least `saving`.
    pub met: bool,
}

pub fn verdict(points: &[Point], default: usize, error_slack: f64, saving: f64) -> Verdict {
    let d = points[default];
    let saving_of = |p: &Point| 1.0 - p.energy_wh_min / d.energy_wh_min;
    let best_within_slack = front(points)
        .into_iter()
        .filter(|&i| points[i].error_m <= (1.0 + error_slack) * d.error_m)
        .filter(|&i| saving_of(&points[i]) > 0.0)
        .max_by(|&a, &b| saving_of(&points[a]).total_cmp(&saving_of(&points[b])));
    let saving_within_slack = best_within_slack.map_or(0.0, |i| saving_of(&points[i]));
    let largest_saving = points
        .iter()
        .filter(|p| p.energy_wh_min.is_finite())
        .map(saving_of)
        .fold(0.0, f64::max);
    Verdict {
        best_within_slack,
        saving_within_slack,
        largest_saving,
        met: saving_within_slack >= saving,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(error_m: f64, energy_wh_min: f64) -> Point {
        Point {
            error_m,
            energy_wh_min,
        }
    }

    #[test]
    fn the_front_keeps_only_undominated_points_in_error_order() {
        let points = [
            p(0.02, 2.0),
            p(0.01, 2.2),
            p(0.03, 2.1), // dominated by the first
            p(0.05, 1.5),
            p(f64::NAN, 1.0), // crashed
        ];
        assert_eq!(front(&points), vec![1, 0, 3]);
    }

    #[test]
    fn the_verdict_finds_a_saving_within_the_error_slack_or_says_there_is_none() {
        let points = [p(0.020, 2.00), p(0.021, 1.70), p(0.050, 1.50)];
        let v = verdict(&points, 0, 0.1, 0.1);
        assert_eq!(v.best_within_slack, Some(1));
        assert!((v.saving_within_slack - 0.15).abs() < 1e-12 && v.met);
        assert!((v.largest_saving - 0.25).abs() < 1e-12);
        // The cheap setting now holds too loosely: nothing within 10 % of the default's error.
        let points = [p(0.020, 2.00), p(0.030, 1.70), p(0.019, 2.05)];
        let v = verdict(&points, 0, 0.1, 0.1);
        assert_eq!(v.best_within_slack, None);
        assert!(!v.met && v.saving_within_slack == 0.0);
    }
}
