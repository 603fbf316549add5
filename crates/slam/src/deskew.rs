//! Motion removed from a revolution: every beam moved to where the sensor was at its first beam.
//!
//! A spinning lidar takes its beams one after another over the turn (0.25 s for the XV-11); a
//! vehicle surveying at 0.5 m/s moves 12 cm in that time, so a revolution taken as one snapshot
//! bends the walls and the map built from it is that much off. The tracker knows how the vehicle
//! moved over the last revolutions, and at constant velocity that motion places each beam. The
//! first beam is the reference because the scan's stamp is its time: the pose the tracker
//! reports for the scan then stays the pose at its stamp.

use plumbline_core::geom::Pose2;
use plumbline_core::scan::sweep::SweepMotion;
use plumbline_core::scan::Scan;

/// The constant rate of `motion` (a relative pose, in the frame of its start) over `dt_s`;
/// `None` when the interval is not positive or the result not finite.
pub fn rate_of(motion: Pose2, dt_s: f32) -> Option<SweepMotion> {
    let rate = SweepMotion {
        velocity_m_s: [motion.x / dt_s, motion.y / dt_s],
        yaw_rate_rad_s: motion.theta / dt_s,
    };
    let finite = rate.velocity_m_s.iter().all(|v| v.is_finite()) && rate.yaw_rate_rad_s.is_finite();
    (dt_s > 0.0 && finite).then_some(rate)
}

/// Poses of the last scans, for the rate the next revolution is de-skewed with.
///
/// The rate is taken over several revolutions, not the last one alone: a scan de-skewed with a
/// rate too high is placed short by about half the excess travel, which makes the next rate too
/// low by as much, and with the last interval alone that loop has a gain of one, so the
/// estimate rings from scan to scan (seen on the XV-11 surveys: steps of 0.34 and -0.08 m
/// alternating at 0.15 m). Over `SPAN_S` the gain falls below 0.7 and the ringing dies out.
#[derive(Clone, Debug, Default)]
pub struct MotionHistory {
    /// (stamp s, pose) of recent scans, oldest first.
    poses: std::collections::VecDeque<(f64, Pose2)>,
}

impl MotionHistory {
    /// How far back the rate is taken, s; never fewer than `MIN_STEPS` scans.
    const SPAN_S: f64 = 0.75;
    const MIN_STEPS: usize = 3;

    pub fn push(&mut self, stamp_s: f64, pose: Pose2) {
        self.poses.push_back((stamp_s, pose));
        while self.poses.len() > Self::MIN_STEPS + 1 && stamp_s - self.poses[1].0 >= Self::SPAN_S {
            self.poses.pop_front();
        }
    }

    pub fn newest_stamp_s(&self) -> Option<f64> {
        self.poses.back().map(|p| p.0)
    }

    /// The mean rate over the history, in the frame of the newest pose; `None` until it spans
    /// `MIN_STEPS` scans.
    pub fn rate(&self) -> Option<SweepMotion> {
        let (&(t0, from), &(t1, to)) = (self.poses.front()?, self.poses.back()?);
        if self.poses.len() <= Self::MIN_STEPS {
            return None;
        }
        let (s, c) = to.theta.sin_cos();
        let (dx, dy) = (to.x - from.x, to.y - from.y);
        let turn = from.between(to).theta;
        let travel = Pose2::new(c * dx + s * dy, c * dy - s * dx, turn);
        rate_of(travel, (t1 - t0) as f32)
    }
}

/// Whether the revolution's beams carry their times (a log without them has every offset zero).
pub fn is_timed<const N: usize>(scan: &Scan<N>) -> bool {
    scan.beams().iter().any(|b| b.time_offset_s != 0.0)
}

/// Writes `scan` de-skewed for `motion` into `out`. A beam that de-skewing puts behind the one
/// before it (hidden from the first beam's viewpoint) or past a full turn (seen twice) is made
/// invalid: the matcher needs the valid beams' bearings in order.
pub fn deskew<const N: usize>(scan: &Scan<N>, motion: SweepMotion, out: &mut Scan<N>) {
    out.clear(scan.stamp_s);
    let [vx, vy] = motion.velocity_m_s;
    let mut first: Option<f32> = None;
    let mut previous = f32::NEG_INFINITY;
    for beam in scan.beams() {
        let mut b = *beam;
        if b.valid {
            let t = b.time_offset_s;
            let (s, c) = (motion.yaw_rate_rad_s * t).sin_cos();
            let p = b.point();
            let (x, y) = (c * p.x - s * p.y + vx * t, s * p.x + c * p.y + vy * t);
            let (sa, ca) = b.angle_rad.sin_cos();
            b.range_m = (x * x + y * y).sqrt();
            b.angle_rad += (ca * y - sa * x).atan2(ca * x + sa * y);
            let bearing = b.angle_rad - *first.get_or_insert(b.angle_rad);
            b.valid = bearing >= previous && bearing <= core::f32::consts::TAU + 1e-3;
            if b.valid {
                previous = bearing;
            }
        }
        // `out` has the input's capacity, so this cannot fail.
        let _ = out.push(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::TAU;
    use plumbline_core::scan::Beam;

    /// Range from (x, y) along `bearing` to the walls of a 6 m x 4 m room centred on the origin.
    fn cast(x: f32, y: f32, bearing: f32) -> f32 {
        let (s, c) = bearing.sin_cos();
        let mut r = f32::INFINITY;
        for (d, wall) in [(c, 3.0 - x), (-c, 3.0 + x), (s, 2.0 - y), (-s, 2.0 + y)] {
            if d > 1e-6 {
                r = r.min(wall / d);
            }
        }
        r
    }

    /// A 360-beam revolution over 0.25 s by a sensor starting at the room's origin facing +x
    /// and moving at `v` (body frame) while turning at `w`: each beam cast from where it was.
    fn smeared(v: [f32; 2], w: f32) -> Scan<360> {
        let mut scan = Scan::new(0.0);
        for k in 0..360 {
            let t = 0.25 * k as f32 / 360.0;
            let heading = w * t;
            let (x, y) = (v[0] * t, v[1] * t);
            let angle = TAU * k as f32 / 360.0;
            let mut beam = Beam::new(angle, cast(x, y, heading + angle));
            beam.time_offset_s = t;
            scan.push(beam).unwrap();
        }
        scan
    }

    /// How far the scan's points (first-beam frame = room frame) lie from the nearest wall, worst.
    fn worst_off_the_walls(scan: &Scan<360>) -> f32 {
        scan.beams()
            .iter()
            .filter(|b| b.valid)
            .map(|b| {
                let p = b.point();
                (3.0 - p.x.abs()).abs().min((2.0 - p.y.abs()).abs())
            })
            .fold(0.0, f32::max)
    }

    #[test]
    fn a_moving_turning_revolution_is_put_back_on_the_walls() {
        let (v, w) = ([0.8, -0.3], 0.6);
        let raw = smeared(v, w);
        let mut fixed = Scan::new(0.0);
        let motion = rate_of(Pose2::new(v[0] * 0.5, v[1] * 0.5, w * 0.5), 0.5);
        deskew(&raw, motion.unwrap(), &mut fixed);
        let (before, after) = (worst_off_the_walls(&raw), worst_off_the_walls(&fixed));
        assert!(before > 0.1, "the test scan is not smeared: {before} m");
        assert!(
            after < 0.01,
            "{after} m off the walls after de-skewing ({before} before)"
        );
        assert!(
            fixed.valid_count() > 340,
            "{} beams kept",
            fixed.valid_count()
        );
    }

    #[test]
    fn de_skewed_bearings_stay_in_order_and_within_a_turn() {
        let mut fixed = Scan::new(0.0);
        let motion = rate_of(Pose2::new(1.0, 0.0, 0.0), 0.5).unwrap();
        deskew(&smeared([2.0, 0.0], 0.0), motion, &mut fixed);
        let valid: Vec<f32> = fixed
            .beams()
            .iter()
            .filter(|b| b.valid)
            .map(|b| b.angle_rad)
            .collect();
        assert!(valid.windows(2).all(|w| w[1] >= w[0]));
        assert!(valid.last().unwrap() - valid[0] <= TAU + 1e-3);
    }

    #[test]
    fn the_rate_is_the_mean_over_several_scans_in_the_newest_frame() {
        let mut history = MotionHistory::default();
        // Heading +90 degrees, moving along world +y at 0.5 m/s on average, but in steps that
        // alternate long and short as a ringing estimate would: body x, 0.5 m/s.
        for k in 0..12 {
            let y = 0.125 * k as f32 + if k % 2 == 1 { 0.05 } else { 0.0 };
            history.push(
                0.25 * k as f64,
                Pose2::new(1.0, y, core::f32::consts::FRAC_PI_2),
            );
            if k < MotionHistory::MIN_STEPS {
                assert!(history.rate().is_none());
            }
        }
        let rate = history.rate().unwrap();
        // The last step alone would say 0.7 m/s.
        assert!((rate.velocity_m_s[0] - 0.5).abs() < 0.1, "{rate:?}");
        assert!(rate.velocity_m_s[1].abs() < 1e-4, "{rate:?}");
        assert!(rate.yaw_rate_rad_s.abs() < 1e-6, "{rate:?}");
    }

    #[test]
    fn untimed_scans_and_bad_intervals_are_recognised() {
        let mut scan: Scan<4> = Scan::new(0.0);
        scan.push(Beam::new(0.0, 1.0)).unwrap();
        assert!(!is_timed(&scan));
        assert!(rate_of(Pose2::new(1.0, 0.0, 0.0), 0.0).is_none());
        assert!(rate_of(Pose2::new(f32::NAN, 0.0, 0.0), 0.1).is_none());
    }
}
