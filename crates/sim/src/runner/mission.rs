//! A mission for the onboard stack: a path flown as a stream of timed setpoints, the way a
//! ground station or companion computer feeds an autopilot (MAVLink
//! SET_POSITION_TARGET_LOCAL_NED). The path is piecewise linear in time through its points, so
//! a square's corners are exact and a curve is as fine as its sampling. Its velocity is the
//! slope of the segment of the moment; its acceleration is that of the velocity interpolated
//! between segment midpoints (at rest before the start and after the end), which is what a
//! path sampled finely from a smooth speed profile speeds up and slows down at.
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

    /// The path's acceleration at `t_s` (m/s^2): the change of velocity between the midpoints
    /// of the segments either side of `t_s`, over the time between them, with the path at rest
    /// at its start and end. `None` outside [start, end].
    pub fn acceleration(&self, t_s: f64) -> Option<[f64; 2]> {
        if !(t_s >= self.start_s() && t_s <= self.end_s()) {
            return None;
        }
        let n = self.points.len();
        // Velocity knots: (time, velocity) at the start (rest), each segment's midpoint, the
        // end (rest). Knot j >= 1 is segment j's midpoint, segment j ending at point j.
        let knot = |j: usize| -> (f64, [f64; 2]) {
            if j == 0 {
                (self.start_s(), [0.0; 2])
            } else if j == n {
                (self.end_s(), [0.0; 2])
            } else {
                let ((t0, a), (t1, b)) = (self.points[j - 1], self.points[j]);
                let span = t1 - t0;
                (
                    0.5 * (t0 + t1),
                    [(b[0] - a[0]) / span, (b[1] - a[1]) / span],
                )
            }
        };
        // The first knot later than t_s, among knots 1..=n (times increase).
        let k = self
            .points
            .partition_point(|(t, _)| *t <= t_s)
            .clamp(1, n - 1);
        let next = if t_s < knot(k).0 { k } else { k + 1 };
        let ((ta, va), (tb, vb)) = (knot(next - 1), knot(next));
        let span = tb - ta;
        Some([(vb[0] - va[0]) / span, (vb[1] - va[1]) / span])
    }

    /// How much later than planned the path starts when the stack first held at `hold_s`, s.
    pub fn shift_for(&self, hold_s: f64) -> f64 {
        (hold_s + SETTLE_BEFORE_START_S - self.start_s()).max(0.0)
    }

    /// The setpoint the stack is sent at `t_s` (heading kept at the power-up heading).
    pub fn setpoint(&self, t_s: f64) -> Option<MissionSetpoint> {
        let (p, v) = self.at(t_s)?;
        let a = self.acceleration(t_s)?;
        Some(MissionSetpoint {
            position_m: [p[0] as f32, p[1] as f32, self.height_m as f32],
            velocity_m_s: [v[0] as f32, v[1] as f32],
            acceleration_m_s2: [a[0] as f32, a[1] as f32],
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
    fn the_acceleration_is_that_of_the_sampled_speed_profile_from_rest_to_rest() {
        // x = t^2 / 2 sampled every 0.05 s for 1 s, then 1 m/s for 1 s: 1 m/s^2, then none.
        let dt = 0.05;
        let mut points: Vec<(f64, [f64; 2])> = (0..=20)
            .map(|k| {
                let t = k as f64 * dt;
                (t, [0.5 * t * t, 0.0])
            })
            .collect();
        points.extend((21..=40).map(|k| {
            let t = k as f64 * dt;
            (t, [0.5 + (t - 1.0), 0.0])
        }));
        let m = Mission::new(points, 1.0).unwrap();
        assert_eq!(m.acceleration(-0.1), None);
        for t in [0.0, 0.01, 0.3, 0.5, 0.97] {
            let a = m.acceleration(t).unwrap();
            assert!((a[0] - 1.0).abs() < 1e-9 && a[1] == 0.0, "{t}: {a:?}");
        }
        for t in [1.03, 1.5, 1.97] {
            let a = m.acceleration(t).unwrap();
            assert!(a[0].abs() < 1e-9, "{t}: {a:?}");
        }
        // The last half segment stops the path: 1 m/s to rest in 25 ms.
        let a = m.acceleration(2.0).unwrap();
        assert!((a[0] + 40.0).abs() < 1e-6, "{a:?}");
        let sp = m.setpoint(0.5).unwrap();
        assert!((sp.acceleration_m_s2[0] - 1.0).abs() < 1e-6, "{sp:?}");
    }

    #[test]
    fn malformed_paths_are_refused() {
        assert!(Mission::new(vec![(0.0, [0.0, 0.0])], 1.0).is_none());
        assert!(Mission::new(vec![(1.0, [0.0, 0.0]), (1.0, [1.0, 0.0])], 1.0).is_none());
        assert!(Mission::new(vec![(0.0, [0.0, 0.0]), (1.0, [f64::NAN, 0.0])], 1.0).is_none());
    }
}
