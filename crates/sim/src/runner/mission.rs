//! A mission for the onboard stack: a path flown as a stream of timed setpoints, the way a
//! ground station or companion computer feeds an autopilot (MAVLink
//! SET_POSITION_TARGET_LOCAL_NED). The path is piecewise linear in time through its points, so
//! a square's corners are exact and a curve is as fine as its sampling.
//!
//! Like a ground station, the sender waits for the vehicle to hold before it starts: the path
//! begins at its own start time or [`SETTLE_BEFORE_START_S`] after the stack first reports
//! Hold, whichever is later, and is shifted in time by the difference ([`Mission::shift_for`]).
//! A vehicle slow to take off (a heavier one) then flies the same path, later.

use plumbline_core::msgs::MissionSetpoint;

/// Hold this long before a mission starts, s.
pub const SETTLE_BEFORE_START_S: f64 = 3.0;

/// Timed points in the estimate frame (origin and heading where the stack powered up).
#[derive(Clone, Debug, PartialEq)]
pub struct Mission {
    /// (time s, position m), times strictly increasing, at least two points.
    points: Vec<(f64, [f64; 2])>,
    height_m: f64,
}

impl Mission {
    /// A mission through `points` at `height_m`; `None` with fewer than two points, times
    /// that do not increase, or a value that is not finite.
    pub fn new(points: Vec<(f64, [f64; 2])>, height_m: f64) -> Option<Self> {
        let finite = points
            .iter()
            .all(|(t, p)| t.is_finite() && p[0].is_finite() && p[1].is_finite());
        let increasing = points.windows(2).all(|w| w[1].0 > w[0].0);
        (points.len() >= 2 && finite && increasing && height_m.is_finite())
            .then_some(Self { points, height_m })
    }

    pub fn start_s(&self) -> f64 {
        self.points[0].0
    }

    pub fn end_s(&self) -> f64 {
        self.points[self.points.len() - 1].0
    }

    /// Where the path is at `t_s` and how fast it moves there (m, m/s); `None` outside
    /// [start, end].
    pub fn at(&self, t_s: f64) -> Option<([f64; 2], [f64; 2])> {
        if !(t_s >= self.start_s() && t_s <= self.end_s()) {
            return None;
        }
        // The segment that ends at the first point later than t (the last one at the end).
        let k = self
            .points
            .partition_point(|(t, _)| *t <= t_s)
            .clamp(1, self.points.len() - 1);
        let ((t0, a), (t1, b)) = (self.points[k - 1], self.points[k]);
        let span = t1 - t0;
        let u = (t_s - t0) / span;
        let position = [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])];
        let velocity = [(b[0] - a[0]) / span, (b[1] - a[1]) / span];
        Some((position, velocity))
    }

    /// How much later than planned the path starts when the stack first held at `hold_s`, s.
    pub fn shift_for(&self, hold_s: f64) -> f64 {
        (hold_s + SETTLE_BEFORE_START_S - self.start_s()).max(0.0)
    }

    /// The setpoint the stack is sent at `t_s` (heading kept at the power-up heading).
    pub fn setpoint(&self, t_s: f64) -> Option<MissionSetpoint> {
        let (p, v) = self.at(t_s)?;
        Some(MissionSetpoint {
            position_m: [p[0] as f32, p[1] as f32, self.height_m as f32],
            velocity_m_s: [v[0] as f32, v[1] as f32],
            yaw_rad: 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_is_linear_between_points_with_its_slope_as_velocity() {
        let m = Mission::new(
            vec![(1.0, [0.0, 0.0]), (3.0, [2.0, 0.0]), (4.0, [2.0, 1.0])],
            1.0,
        )
        .unwrap();
        assert_eq!(m.at(0.5), None);
        assert_eq!(m.at(1.0), Some(([0.0, 0.0], [1.0, 0.0])));
        assert_eq!(m.at(2.0), Some(([1.0, 0.0], [1.0, 0.0])));
        assert_eq!(m.at(3.5), Some(([2.0, 0.5], [0.0, 1.0])));
        assert_eq!(m.at(4.0), Some(([2.0, 1.0], [0.0, 1.0])));
        assert_eq!(m.at(4.1), None);
        let sp = m.setpoint(2.0).unwrap();
        assert_eq!(
            (sp.position_m, sp.velocity_m_s),
            ([1.0, 0.0, 1.0], [1.0, 0.0])
        );
    }

    #[test]
    fn malformed_paths_are_refused() {
        assert!(Mission::new(vec![(0.0, [0.0, 0.0])], 1.0).is_none());
        assert!(Mission::new(vec![(1.0, [0.0, 0.0]), (1.0, [1.0, 0.0])], 1.0).is_none());
        assert!(Mission::new(vec![(0.0, [0.0, 0.0]), (1.0, [f64::NAN, 0.0])], 1.0).is_none());
    }
}
