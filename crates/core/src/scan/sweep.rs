//! De-skewing: the points of one revolution moved to where the sensor was at mid-revolution.
//!
//! A spinning lidar takes its beams one after another over the turn (0.2 s for the XV-11). At
//! the 1 m/s of the swing after seed 000's push the sensor moves 0.2 m in that time, so the
//! revolution is a smeared picture of the room, and a keyframe taken mid-swing keeps the smear:
//! one hold in about sixty lost 10 cm of estimate that way. Each beam is taken back to the
//! mid-revolution frame with the estimated velocity and the gyro's yaw rate, the frame the
//! estimator already assigns the match to (`estimate/scan_match.rs`).

use crate::fast_math::sin_cos;

/// How the sensor moved during the revolution, in the levelled heading frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepMotion {
    /// Horizontal velocity along the sensor's x and y, m/s.
    pub velocity_m_s: [f32; 2],
    /// Turn rate about the vertical, counter-clockwise positive, rad/s.
    pub yaw_rate_rad_s: f32,
}

/// The correction of one revolution: the motion and the beam time it refers to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sweep {
    motion: SweepMotion,
    /// Beam time of mid-revolution, s after the first beam.
    mid_s: f32,
}

impl Sweep {
    /// `None` when there is nothing to correct: the beams carry no timing (a driver that does
    /// not know it, logs) or the motion is zero or not finite.
    pub(crate) fn new(motion: SweepMotion, first_s: f32, last_s: f32) -> Option<Self> {
        let [vx, vy] = motion.velocity_m_s;
        let w = motion.yaw_rate_rad_s;
        let finite = vx.is_finite() && vy.is_finite() && w.is_finite();
        let moving = vx != 0.0 || vy != 0.0 || w != 0.0;
        let timed = first_s.is_finite() && last_s.is_finite() && last_s > first_s;
        (finite && moving && timed).then_some(Self {
            motion,
            mid_s: 0.5 * (first_s + last_s),
        })
    }

    /// A hit at (`x`, `y`) in the sensor's levelled frame, taken `time_offset_s` after the first
    /// beam, seen from mid-revolution: turned by the yaw since then and moved by the
    /// displacement. Inlined: it runs on every beam.
    #[inline]
    pub(crate) fn seen_from_mid(&self, (x, y): (f32, f32), time_offset_s: f32) -> (f32, f32) {
        let dt = time_offset_s - self.mid_s;
        let turn = self.motion.yaw_rate_rad_s * dt;
        // Within a revolution a hovering vehicle turns by milliradians: short series there
        // (first omitted terms under 2e-9 below 0.1 rad), the general sine and cosine beyond.
        let (st, ct) = if libm::fabsf(turn) <= 0.1 {
            let t2 = turn * turn;
            (
                turn * (1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0))),
                1.0 - t2 * (0.5 - t2 * (1.0 / 24.0)),
            )
        } else {
            sin_cos(turn)
        };
        let [vx, vy] = self.motion.velocity_m_s;
        (ct * x - st * y + vx * dt, st * x + ct * y + vy * dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::level::{Leveller, ScanPlane};
    use crate::scan::{Beam, Scan};
    use core::f32::consts::TAU;

    /// Range from (x, y) along `bearing` to the walls of a 6 m x 4 m room centred on the origin.
    fn cast(x: f32, y: f32, bearing: f32) -> f32 {
        let (s, c) = libm::sincosf(bearing);
        let mut r = f32::INFINITY;
        for (d, wall) in [(c, 3.0 - x), (-c, 3.0 + x), (s, 2.0 - y), (-s, 2.0 + y)] {
            if d > 1e-6 {
                r = r.min(wall / d);
            }
        }
        r
    }

    /// How far a point (mid-revolution frame = room frame) lies from the nearest wall.
    fn off_the_walls(range: f32, angle: f32) -> f32 {
        let (s, c) = libm::sincosf(angle);
        let (x, y) = (range * c, range * s);
        (3.0 - x.abs()).abs().min((2.0 - y.abs()).abs())
    }

    /// A 360-beam revolution over 0.2 s by a sensor that moves at `v` and turns at `w`, its pose
    /// at mid-revolution being the room's origin: each beam is cast from where the sensor was.
    fn smeared(v: [f32; 2], w: f32) -> Scan<360> {
        let mut scan = Scan::new(0.0);
        let (n, period) = (360, 0.2f32);
        let mid = 0.5 * period * (n - 1) as f32 / n as f32;
        for k in 0..n {
            // Times start mid-scan and wrap, as the XV-11's do.
            let t = period * ((k + n / 2) % n) as f32 / n as f32;
            let dt = t - mid;
            let a = TAU * k as f32 / n as f32 - 3.1;
            let mut beam = Beam::new(a, cast(v[0] * dt, v[1] * dt, a + w * dt));
            beam.time_offset_s = t;
            scan.push(beam).unwrap();
        }
        scan
    }

    fn worst_offset(scan: &Scan<360>) -> f32 {
        scan.beams()
            .iter()
            .map(|b| off_the_walls(b.range_m, b.angle_rad))
            .fold(0.0, f32::max)
    }

    #[test]
    fn a_smeared_revolution_is_taken_back_onto_the_walls() {
        // The swing after seed 000's push, and a quick turn.
        let motion = SweepMotion {
            velocity_m_s: [1.0, -0.4],
            yaw_rate_rad_s: 0.8,
        };
        let scan = smeared(motion.velocity_m_s, motion.yaw_rate_rad_s);
        let mut leveller = Leveller::<360>::default();
        let raw = worst_offset(leveller.level(&scan, ScanPlane::LEVEL, SweepMotion::default()));
        let fixed = worst_offset(leveller.level(&scan, ScanPlane::LEVEL, motion));
        assert!(raw > 0.05, "the smear should be visible: {raw} m");
        assert!(
            fixed < 1e-3,
            "{fixed} m off the walls after de-skewing ({raw} before)"
        );
    }

    #[test]
    fn a_de_skewed_revolution_keeps_the_angular_order_the_matcher_needs() {
        // Exploring speed: the corrected bearings of the first and last beams overlap, and at
        // the seam of the beam times (mid-scan) they step backwards.
        let motion = SweepMotion {
            velocity_m_s: [0.5, 0.3],
            yaw_rate_rad_s: 0.0,
        };
        let scan = smeared(motion.velocity_m_s, motion.yaw_rate_rad_s);
        let mut leveller = Leveller::<360>::default();
        let out = leveller.level(&scan, 0.0, 0.0, motion);
        let mut order = crate::scan::AngularOrder::default();
        let kept: usize = out
            .beams()
            .iter()
            .filter(|b| b.valid)
            .map(|b| usize::from(order.admits(b.angle_rad)))
            .sum();
        let valid = out.beams().iter().filter(|b| b.valid).count();
        assert_eq!(kept, valid, "a kept beam is out of order");
        assert!((350..360).contains(&valid), "{valid} of 360 beams kept");
    }

    #[test]
    fn nothing_is_moved_without_beam_times_or_a_finite_motion() {
        let moving = SweepMotion {
            velocity_m_s: [1.0, 0.0],
            yaw_rate_rad_s: 0.0,
        };
        assert!(Sweep::new(moving, 0.0, 0.0).is_none(), "untimed beams");
        assert!(Sweep::new(SweepMotion::default(), 0.0, 0.2).is_none());
        let nan = SweepMotion {
            velocity_m_s: [f32::NAN, 0.0],
            yaw_rate_rad_s: 0.0,
        };
        assert!(Sweep::new(nan, 0.0, 0.2).is_none());
        let mut untimed = Scan::<360>::new(0.0);
        for b in smeared([0.0, 0.0], 0.0).beams() {
            untimed.push(Beam::new(b.angle_rad, b.range_m)).unwrap();
        }
        let mut leveller = Leveller::<360>::default();
        let still = leveller
            .level(&untimed, ScanPlane::LEVEL, SweepMotion::default())
            .clone();
        let out = leveller.level(&untimed, ScanPlane::LEVEL, moving);
        assert!(out.beams() == still.beams(), "untimed beams were moved");
    }
}
