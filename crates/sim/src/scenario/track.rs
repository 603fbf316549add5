//! `track`: the onboard stack takes off, holds, then flies a path fed to it as a mission (a
//! setpoint stream, as a ground station would send it): a 3 m x 3 m square from the start, or
//! a figure of eight through the start, three laps at 1 m/s, then holds at the start. Scored
//! on how closely the true position follows the setpoint (tracking error), and on the hold
//! before and after. Model errors and gust storms (`SimConfig::model_error`, `gusts`) are
//! what the controllers are compared under.

use super::flight::{Entry, Flight, Options, ScenarioError};
use super::onboard::{self, ARM_AT_S};
use crate::runner::mission::Mission;
use crate::runner::onboard_link::{autopilot_for, Script};
use crate::runner::SimConfig;

pub(super) const ENTRY: Entry = Entry {
    name: "track",
    about: "fly a 3 m x 3 m square (or a figure of eight) at 1 m/s, three laps, then hold",
    prepare,
};

/// The path the `track` scenario flies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TrackShape {
    /// A 3 m x 3 m square with a corner at the start: forward 3 m, left 3 m, back, right,
    /// stopping at each corner.
    #[default]
    Square,
    /// A figure of eight of two 0.75 m circles (a 3 m x 1.5 m box) crossing at the start,
    /// flown without stopping.
    Eight,
}

impl TrackShape {
    pub fn name(self) -> &'static str {
        match self {
            TrackShape::Square => "square",
            TrackShape::Eight => "eight",
        }
    }
}

/// The mission starts here: the stack has been holding for several seconds, s.
pub const TRACK_START_S: f64 = 8.0;
/// Side of the square and length of the eight, m.
pub const TRACK_SIZE_M: f64 = 3.0;
/// Cruise speed along the path, m/s.
pub const TRACK_SPEED_MPS: f64 = 1.0;
/// Acceleration of the setpoint when it starts and stops, m/s²: a corner taken at full speed
/// would ask for an instant reversal, which tilts the vehicle (and its lidar) as far as the
/// controller allows; a mission planner limits it the same way.
pub const TRACK_ACCEL_MPS2: f64 = 1.0;
pub const TRACK_LAPS: usize = 3;
/// How long the run goes on after the last lap would end if the mission started on time,
/// when the options give no duration: room for a late start (a heavy vehicle's slow take-off)
/// and a hold error after the settling, s.
const HOLD_AFTER_S: f64 = 20.0;
/// Room the path must leave around the vehicle, beyond its radius: tracking errors under model
/// error reach a few decimetres, m.
const TRACK_MARGIN_M: f64 = 0.5;
/// Spacing of the points the path is sampled at, m (the speed profile is exact at them).
const STEP_M: f64 = 0.02;

/// The runs of `shape` in the estimate frame (x along the start heading): the setpoint stops
/// at the end of each run. Each run is a polyline sampled every `STEP_M` or finer.
fn runs(shape: TrackShape) -> Vec<Vec<[f64; 2]>> {
    let s = TRACK_SIZE_M;
    match shape {
        TrackShape::Square => {
            let corners = [[0.0, 0.0], [s, 0.0], [s, s], [0.0, s], [0.0, 0.0]];
            let edges: Vec<Vec<[f64; 2]>> = corners
                .windows(2)
                .map(|w| {
                    let n = (s / STEP_M).ceil() as usize;
                    (0..=n)
                        .map(|k| {
                            let u = k as f64 / n as f64;
                            [
                                w[0][0] + u * (w[1][0] - w[0][0]),
                                w[0][1] + u * (w[1][1] - w[0][1]),
                            ]
                        })
                        .collect()
                })
                .collect();
            (0..TRACK_LAPS).flat_map(|_| edges.clone()).collect()
        }
        TrackShape::Eight => {
            let r = 0.25 * s;
            let n = (core::f64::consts::TAU * r / STEP_M).ceil() as usize;
            let mut path = vec![[0.0, 0.0]];
            for _ in 0..TRACK_LAPS {
                // Clockwise round the right circle, then anticlockwise round the left one: both
                // leave the start heading along +y, so the crossing is smooth.
                for side in [1.0, -1.0] {
                    path.extend((1..=n).map(|k| {
                        let a = core::f64::consts::TAU * k as f64 / n as f64;
                        [side * r * (1.0 - a.cos()), r * a.sin()]
                    }));
                }
            }
            vec![path]
        }
    }
}

/// Time to cover `s` of a run of length `length` that starts and ends at rest, with the
/// track's acceleration and cruise speed (a trapezoidal speed profile), s.
fn trapezoid_time(s: f64, length: f64) -> f64 {
    let (v, a) = (TRACK_SPEED_MPS, TRACK_ACCEL_MPS2);
    let ramp_m = (0.5 * v * v / a).min(0.5 * length);
    let peak = (2.0 * a * ramp_m).sqrt();
    let total = 2.0 * peak / a + (length - 2.0 * ramp_m) / v;
    if s <= ramp_m {
        (2.0 * s / a).sqrt()
    } else if s <= length - ramp_m {
        peak / a + (s - ramp_m) / v
    } else {
        total - (2.0 * (length - s).max(0.0) / a).sqrt()
    }
}

/// `TRACK_LAPS` laps of `shape` from `TRACK_START_S`, at `height_m`.
pub fn mission(shape: TrackShape, height_m: f64) -> Mission {
    let mut points = vec![(TRACK_START_S, [0.0, 0.0])];
    let mut t0 = TRACK_START_S;
    for run in runs(shape) {
        let mut along = 0.0;
        let lengths: Vec<f64> = run
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .collect();
        let length: f64 = lengths.iter().sum();
        for (p, d) in run[1..].iter().zip(&lengths) {
            along += d;
            points.push((t0 + trapezoid_time(along, length), *p));
        }
        t0 += trapezoid_time(length, length);
    }
    Mission::new(points, height_m).expect("the track's points are finite and their times increase")
}

/// `p` in the estimate frame as a world point, given the start pose (x, y, yaw).
pub fn to_world(start: [f64; 3], p: [f64; 2]) -> [f64; 2] {
    let (sin, cos) = start[2].sin_cos();
    [
        start[0] + cos * p[0] - sin * p[1],
        start[1] + sin * p[0] + cos * p[1],
    ]
}

fn prepare(options: &Options, config: &mut SimConfig) -> Result<Flight, ScenarioError> {
    // The world's people walk unless the caller left them out.
    let people = config.people;
    onboard::setup(ENTRY.name, options, config)?;
    config.people = people;
    // The path is flown at the height the stack holds after take-off.
    let height_m = autopilot_for(&config.vehicle).supervisor.takeoff_height_m;
    let mission = mission(options.track, f64::from(height_m));
    if options.duration_s.is_none() {
        config.max_duration_s = mission.end_s() + HOLD_AFTER_S;
    }
    let radius = config.vehicle.radius_m + TRACK_MARGIN_M;
    let what = format!(
        "the {} track's point (it needs {TRACK_MARGIN_M} m beyond the vehicle radius; \
         world hall fits it)",
        options.track.name()
    );
    for p in runs(options.track).iter().flatten() {
        let p = to_world(config.world.start, *p);
        config
            .world
            .check_free(p, radius, &what)
            .map_err(ScenarioError::World)?;
    }
    let script = Script {
        mission: Some(mission),
        ..Script::arm_at(ARM_AT_S)
    };
    onboard::flight(options, config, script, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest speed and acceleration of the setpoint, sampled every `dt`.
    fn limits(m: &Mission, dt: f64) -> (f64, f64) {
        let (mut speed, mut accel) = (0.0f64, 0.0f64);
        let mut t = m.start_s();
        let mut before = m.at(t).unwrap().1;
        while t + dt <= m.end_s() {
            t += dt;
            let v = m.at(t).unwrap().1;
            speed = speed.max(v[0].hypot(v[1]));
            accel = accel.max((v[0] - before[0]).hypot(v[1] - before[1]) / dt);
            before = v;
        }
        (speed, accel)
    }

    #[test]
    fn the_square_cruises_at_the_track_speed_stops_at_corners_and_closes() {
        let m = mission(TrackShape::Square, 1.0);
        // Each edge: a second to speed up, two at cruise, a second to stop.
        let edge_s = 4.0;
        let lap_s = 4.0 * edge_s;
        assert_eq!(m.start_s(), TRACK_START_S);
        assert!((m.end_s() - (TRACK_START_S + TRACK_LAPS as f64 * lap_s)).abs() < 1e-9);
        let (p, v) = m.at(TRACK_START_S + 2.0).unwrap();
        assert!((p[0] - 1.5).abs() < 1e-3 && p[1] == 0.0, "{p:?}");
        assert!((v[0] - 1.0).abs() < 1e-3 && v[1] == 0.0, "{v:?}");
        let (corner, v) = m.at(TRACK_START_S + edge_s).unwrap();
        assert!(
            (corner[0] - 3.0).abs() < 1e-12 && v[0].hypot(v[1]) < 0.25,
            "{v:?}"
        );
        let (p, _) = m.at(TRACK_START_S + lap_s).unwrap();
        assert!(p[0].abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
        // Over half a second, so the sampling's chords average out.
        let (speed, accel) = limits(&m, 0.5);
        assert!(speed <= TRACK_SPEED_MPS + 1e-9, "{speed}");
        assert!(accel < 1.1 * TRACK_ACCEL_MPS2, "{accel}");
    }

    #[test]
    fn the_eight_crosses_at_the_start_within_its_box_at_the_track_speed() {
        let m = mission(TrackShape::Eight, 1.0);
        let mut t = m.start_s();
        while t <= m.end_s() {
            let (p, _) = m.at(t).unwrap();
            assert!(p[0].abs() <= 0.5 * TRACK_SIZE_M + 1e-9, "{p:?}");
            assert!(p[1].abs() <= 0.25 * TRACK_SIZE_M + 1e-9, "{p:?}");
            t += 0.01;
        }
        let (end, _) = m.at(m.end_s()).unwrap();
        assert!(end[0].abs() < 1e-9 && end[1].abs() < 1e-9);
        let (_, v) = m.at(m.start_s() + 5.0).unwrap();
        assert!((v[0].hypot(v[1]) - TRACK_SPEED_MPS).abs() < 1e-3, "{v:?}");
        // The circles' 0.75 m radius at 1 m/s: 1.33 m/s².
        let (speed, accel) = limits(&m, 0.5);
        assert!(speed <= TRACK_SPEED_MPS + 1e-9, "{speed}");
        assert!(accel < 1.4, "{accel}");
    }
}
