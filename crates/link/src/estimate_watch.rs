//! Whether the autopilot's estimate, read back over MAVLink, may guess a lidar revolution's
//! motion at a given moment, and why not when it may not.
//!
//! A guess spans the time between two revolutions, so the estimate at both ends must be the
//! autopilot's current one and one continuous track. It is withheld ([`Withheld`]) when no
//! estimate ever came, when the newest is older than the timeout (the autopilot stopped
//! sending, as PX4 and ArduPilot do while they have no position), when it is not usable (a
//! NaN, ODOMETRY with quality -1 or in an unreadable frame), and for the one revolution where
//! the track broke: the autopilot's clock went back (a reboot) or leapt ahead of the
//! companion's, ODOMETRY's reset counter changed, or the estimate switched between ODOMETRY
//! and LOCAL_POSITION_NED with ATTITUDE. Plumbline's motion rule
//! (`plumbline_slam::EstimatedMotion`) then gives no guess until two usable readings in a row,
//! and the SLAM falls back on its own lidar-only guess.
//!
//! The age of a sample is measured on the companion's clock from the autopilot's stamp plus
//! the smallest delay seen so far, not from when it was read: a sample that sat in a busy
//! serial buffer is as old as its stamp says.

use crate::estimate_in::{EstimatePart, EstimateSample, OdometryPose};
use plumbline_core::msgs::EstimatedState;

/// A sample whose stamp is this much further ahead of the companion's clock than the smallest
/// delay seen says the autopilot's clock leapt forward (s).
const CLOCK_LEAP_S: f64 = 0.5;

/// How fast the delay floor may rise (s per s of the autopilot's clock): two crystals drift
/// apart by well under this, and a queue that delays samples for a while barely lifts it.
const DRIFT_ALLOWANCE: f64 = 1e-3;

/// Why a revolution gets no estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Withheld {
    /// No estimate message has come from the autopilot.
    Missing,
    /// The newest is older than the timeout.
    Stale,
    /// Fresh but unusable: a NaN, or the autopilot says it failed.
    Invalid,
    /// The autopilot's track broke since the previous revolution.
    Discontinuity,
}

/// A value with the autopilot's stamp and the delay floor of its kind.
#[derive(Clone, Copy, Debug)]
struct Stamped<T> {
    value: T,
    autopilot_s: f64,
    /// Smallest `arrival - stamp` seen since this kind's clock was last continuous (s).
    delay_floor_s: f64,
}

impl<T> Stamped<T> {
    /// When the sample was taken, on the companion's clock.
    fn taken_s(&self) -> f64 {
        self.autopilot_s + self.delay_floor_s
    }
}

/// Stores a new sample in `slot`; true when its stamp breaks the kind's clock.
fn update<T>(slot: &mut Option<Stamped<T>>, value: T, autopilot_s: f64, arrival_s: f64) -> bool {
    let delay = arrival_s - autopilot_s;
    let (jumped, floor) = match slot {
        Some(p) => {
            let allowed = p.delay_floor_s + DRIFT_ALLOWANCE * (autopilot_s - p.autopilot_s);
            let jumped = autopilot_s < p.autopilot_s || delay < p.delay_floor_s - CLOCK_LEAP_S;
            (jumped, if jumped { delay } else { delay.min(allowed) })
        }
        None => (false, delay),
    };
    *slot = Some(Stamped {
        value,
        autopilot_s,
        delay_floor_s: floor,
    });
    jumped
}

/// Where a reading's estimate came from (a switch breaks the track).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    Odometry,
    PositionHeading,
}

/// The autopilot's estimate samples as they arrive, judged at each revolution.
#[derive(Clone, Debug)]
pub struct EstimateWatch {
    timeout_s: f64,
    pose: Option<Stamped<OdometryPose>>,
    position: Option<Stamped<[f32; 3]>>,
    heading: Option<Stamped<f32>>,
    /// A clock broke since the previous reading.
    broken: bool,
    /// The previous reading's source and ODOMETRY reset counter, while fresh.
    last: Option<(Source, Option<u8>)>,
}

impl EstimateWatch {
    /// Samples older than `timeout_s` are stale.
    pub fn new(timeout_s: f64) -> Self {
        Self {
            timeout_s,
            pose: None,
            position: None,
            heading: None,
            broken: false,
            last: None,
        }
    }

    /// A sample read at `arrival_s` (the companion's monotonic clock, s).
    pub fn take(&mut self, sample: &EstimateSample, arrival_s: f64) {
        let t = sample.autopilot_s;
        self.broken |= match sample.part {
            EstimatePart::Pose(pose) => update(&mut self.pose, pose, t, arrival_s),
            EstimatePart::Position { position_m } => {
                update(&mut self.position, position_m, t, arrival_s)
            }
            EstimatePart::Heading { yaw_rad } => update(&mut self.heading, yaw_rad, t, arrival_s),
        };
    }

    /// The estimate at `now_s` (the clock of [`Self::take`]), or why there is none. ODOMETRY
    /// is preferred while fresh: it carries the autopilot's own verdict and reset counter.
    pub fn reading(&mut self, now_s: f64) -> Result<EstimatedState, Withheld> {
        let fresh = |taken_s: f64| now_s - taken_s <= self.timeout_s;
        let chosen = match (self.pose, self.position, self.heading) {
            (Some(p), ..) if fresh(p.taken_s()) => Some((
                Source::Odometry,
                p.value.position_m,
                p.value.yaw_rad,
                p.value.valid,
                Some(p.value.reset_counter),
            )),
            (_, Some(p), Some(h)) if fresh(p.taken_s()) && fresh(h.taken_s()) => {
                Some((Source::PositionHeading, p.value, h.value, true, None))
            }
            _ => None,
        };
        let broken = core::mem::take(&mut self.broken);
        let Some((source, position_m, yaw_rad, valid, reset)) = chosen else {
            self.last = None;
            let any = self.pose.is_some() || self.position.is_some() || self.heading.is_some();
            return Err(if any {
                Withheld::Stale
            } else {
                Withheld::Missing
            });
        };
        let switched = self.last.is_some_and(|last| last != (source, reset));
        self.last = Some((source, reset));
        if broken || switched {
            return Err(Withheld::Discontinuity);
        }
        let finite = position_m.iter().take(2).all(|v| v.is_finite()) && yaw_rad.is_finite();
        if !(valid && finite) {
            return Err(Withheld::Invalid);
        }
        Ok(EstimatedState {
            position_m,
            yaw_rad,
            valid: true,
            ..EstimatedState::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const TIMEOUT_S: f64 = 0.5;

    fn position(t: f64, x: f32) -> EstimateSample {
        EstimateSample {
            autopilot_s: t,
            part: EstimatePart::Position {
                position_m: [x, 0.0, 1.0],
            },
        }
    }

    fn heading(t: f64, yaw_rad: f32) -> EstimateSample {
        EstimateSample {
            autopilot_s: t,
            part: EstimatePart::Heading { yaw_rad },
        }
    }

    fn pose(t: f64, x: f32, valid: bool, reset_counter: u8) -> EstimateSample {
        EstimateSample {
            autopilot_s: t,
            part: EstimatePart::Pose(OdometryPose {
                position_m: [x, 0.0, 1.0],
                yaw_rad: 0.3,
                valid,
                reset_counter,
            }),
        }
    }

    /// Position and heading at autopilot time `t`, read at `arrival_s`.
    fn both_at(w: &mut EstimateWatch, t: f64, x: f32, arrival_s: f64) {
        w.take(&position(t, x), arrival_s);
        w.take(&heading(t, 0.3), arrival_s);
    }

    /// Position and heading at autopilot time `t`, read 20 ms later on a clock 100 s ahead.
    fn both(w: &mut EstimateWatch, t: f64, x: f32) {
        both_at(w, t, x, t + 100.02);
    }

    #[test]
    fn position_and_heading_make_an_estimate_until_they_go_stale() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        assert_eq!(w.reading(100.0), Err(Withheld::Missing));
        both(&mut w, 1.0, 2.0);
        let e = w.reading(101.1).unwrap();
        assert_eq!(
            (e.position_m, e.yaw_rad, e.valid),
            ([2.0, 0.0, 1.0], 0.3, true)
        );
        // Still fresh half a second after it was taken, stale after that.
        assert!(w.reading(101.5).is_ok());
        assert_eq!(w.reading(101.6), Err(Withheld::Stale));
        // The position alone does not make an estimate.
        w.take(&position(1.7, 2.5), 101.72);
        assert_eq!(w.reading(101.75), Err(Withheld::Stale));
        w.take(&heading(1.7, 0.3), 101.72);
        assert!(w.reading(101.75).is_ok());
    }

    #[test]
    fn a_sample_that_waited_in_a_buffer_is_as_old_as_its_stamp() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        both(&mut w, 1.0, 0.0);
        assert!(w.reading(101.05).is_ok());
        // Taken at 1.1 but read 0.8 s later (a busy serial line): stale, not a leap.
        both_at(&mut w, 1.1, 0.1, 101.9);
        assert_eq!(w.reading(101.9), Err(Withheld::Stale));
        both(&mut w, 2.0, 0.5);
        assert!(w.reading(102.05).is_ok());
    }

    #[test]
    fn nan_fields_and_a_failed_odometry_are_invalid() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        w.take(&position(1.0, f32::NAN), 101.0);
        w.take(&heading(1.0, 0.0), 101.0);
        assert_eq!(w.reading(101.0), Err(Withheld::Invalid));
        w.take(&position(1.1, 0.0), 101.1);
        w.take(&heading(1.1, f32::INFINITY), 101.1);
        assert_eq!(w.reading(101.1), Err(Withheld::Invalid));
        let mut w = EstimateWatch::new(TIMEOUT_S);
        w.take(&pose(1.0, 0.0, false, 0), 101.0);
        assert_eq!(w.reading(101.0), Err(Withheld::Invalid));
        w.take(&pose(1.1, 0.0, true, 0), 101.1);
        assert!(w.reading(101.1).is_ok());
    }

    #[test]
    fn the_autopilot_clock_going_back_or_leaping_ahead_breaks_the_track_once() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        both_at(&mut w, 50.0, 0.0, 150.02);
        assert!(w.reading(150.03).is_ok());
        // A reboot: time since boot starts again.
        both_at(&mut w, 0.2, 0.0, 150.22);
        assert_eq!(w.reading(150.25), Err(Withheld::Discontinuity));
        both_at(&mut w, 0.3, 0.1, 150.32);
        assert!(w.reading(150.35).is_ok());
        // Ten seconds ahead within a tenth of a second of the companion's clock.
        both_at(&mut w, 10.4, 0.2, 150.45);
        assert_eq!(w.reading(150.46), Err(Withheld::Discontinuity));
        both_at(&mut w, 10.5, 0.3, 150.55);
        assert!(w.reading(150.56).is_ok(), "the new clock is taken as it is");
        // A silence of a few seconds is no leap: the stamps follow the companion's clock.
        both_at(&mut w, 14.5, 0.3, 154.52);
        assert!(w.reading(154.55).is_ok());
    }

    #[test]
    fn a_slow_drift_between_the_clocks_never_makes_the_estimate_stale() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        // The autopilot's crystal 200 ppm slow, for two hours at 10 Hz.
        for i in 0..72_000 {
            let t = f64::from(i) * 0.1;
            let arrival = t * (1.0 + 2e-4) + 0.01;
            w.take(&position(t, 0.0), arrival);
            w.take(&heading(t, 0.0), arrival);
            if i % 1000 == 0 {
                assert!(w.reading(arrival).is_ok(), "stale at {t} s");
            }
        }
    }

    #[test]
    fn odometry_is_preferred_and_a_reset_or_a_switch_breaks_the_track() {
        let mut w = EstimateWatch::new(TIMEOUT_S);
        both(&mut w, 1.0, 5.0);
        assert_eq!(w.reading(101.03).unwrap().position_m[0], 5.0);
        w.take(&pose(1.05, 7.0, true, 2), 101.07);
        assert_eq!(w.reading(101.08), Err(Withheld::Discontinuity));
        w.take(&pose(1.1, 7.1, true, 2), 101.12);
        assert_eq!(w.reading(101.13).unwrap().position_m[0], 7.1);
        // The autopilot's estimate jumped: its reset counter says so.
        w.take(&pose(1.2, 9.0, true, 3), 101.22);
        assert_eq!(w.reading(101.23), Err(Withheld::Discontinuity));
        w.take(&pose(1.3, 9.1, true, 3), 101.32);
        assert!(w.reading(101.33).is_ok());
        // ODOMETRY stops; position and heading carry on as another track.
        both(&mut w, 2.0, 9.5);
        assert_eq!(w.reading(102.03), Err(Withheld::Discontinuity));
        both(&mut w, 2.1, 9.6);
        assert_eq!(w.reading(102.13).unwrap().position_m[0], 9.6);
    }

    fn any_f32() -> impl Strategy<Value = f32> {
        prop_oneof![
            -1e4f32..1e4,
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(f32::MAX),
        ]
    }

    fn any_sample() -> impl Strategy<Value = EstimateSample> {
        let part = prop_oneof![
            (any_f32(), any_f32(), any::<bool>(), any::<u8>()).prop_map(|(x, yaw, valid, r)| {
                EstimatePart::Pose(OdometryPose {
                    position_m: [x, -x, 1.0],
                    yaw_rad: yaw,
                    valid,
                    reset_counter: r,
                })
            }),
            any_f32().prop_map(|x| EstimatePart::Position {
                position_m: [x, 1.0, 1.0]
            }),
            any_f32().prop_map(|yaw_rad| EstimatePart::Heading { yaw_rad }),
        ];
        (0.0f64..5e6, part).prop_map(|(autopilot_s, part)| EstimateSample { autopilot_s, part })
    }

    proptest! {
        #[test]
        fn whatever_arrives_only_a_finite_fresh_estimate_gets_through(
            stream in proptest::collection::vec((any_sample(), 0.0f64..1.0), 1..60),
        ) {
            let mut w = EstimateWatch::new(TIMEOUT_S);
            let mut now = 0.0;
            for (sample, wait_s) in &stream {
                now += wait_s;
                w.take(sample, now);
                if let Ok(e) = w.reading(now) {
                    prop_assert!(e.valid && e.yaw_rad.is_finite());
                    prop_assert!(e.position_m[..2].iter().all(|v| v.is_finite()));
                }
            }
            // Long after the last sample nothing is fresh.
            prop_assert_eq!(w.reading(now + 1e7), Err(Withheld::Stale));
        }
    }
}
