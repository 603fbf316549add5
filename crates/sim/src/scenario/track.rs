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
    /// A 3 m x 3 m square with a corner at the start: forward 3 m, left 3 m, back, right.
    #[default]
    Square,
    /// A figure of eight in a 3 m x 3 m box centred on the start, crossing at the start.
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
/// Side of the square and size of the eight's box, m.
pub const TRACK_SIZE_M: f64 = 3.0;
/// Speed along the path, m/s.
pub const TRACK_SPEED_MPS: f64 = 1.0;
pub const TRACK_LAPS: usize = 3;
/// Room the path must leave around the vehicle, beyond its radius: tracking errors under model
/// error reach a few decimetres, m.
const TRACK_MARGIN_M: f64 = 0.5;
/// Points per lap of the figure of eight (its chords are within a millimetre of the curve).
const EIGHT_POINTS: usize = 400;

/// One lap of `shape` in the estimate frame (x along the start heading), from the start.
fn lap(shape: TrackShape) -> Vec<[f64; 2]> {
    let s = TRACK_SIZE_M;
    match shape {
        TrackShape::Square => vec![[0.0, 0.0], [s, 0.0], [s, s], [0.0, s], [0.0, 0.0]],
        TrackShape::Eight => (0..=EIGHT_POINTS)
            .map(|k| {
                let phi = core::f64::consts::TAU * k as f64 / EIGHT_POINTS as f64;
                [0.5 * s * phi.sin(), 0.5 * s * (2.0 * phi).sin()]
            })
            .collect(),
    }
}

/// `TRACK_LAPS` laps of `shape` at `TRACK_SPEED_MPS` from `TRACK_START_S`, at `height_m`:
/// each point's time is its distance along the path over the speed.
pub fn mission(shape: TrackShape, height_m: f64) -> Mission {
    let one = lap(shape);
    let mut points = vec![(TRACK_START_S, one[0])];
    let mut t = TRACK_START_S;
    for _ in 0..TRACK_LAPS {
        for w in one.windows(2) {
            t += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / TRACK_SPEED_MPS;
            points.push((t, w[1]));
        }
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
    onboard::setup(ENTRY.name, options, config)?;
    // The path is flown at the height the stack holds after take-off.
    let height_m = autopilot_for(&config.vehicle).supervisor.takeoff_height_m;
    let mission = mission(options.track, f64::from(height_m));
    let radius = config.vehicle.radius_m + TRACK_MARGIN_M;
    let what = format!(
        "the {} track's point (it needs {TRACK_MARGIN_M} m beyond the vehicle radius; \
         world hall fits it)",
        options.track.name()
    );
    for p in lap(options.track) {
        let p = to_world(config.world.start, p);
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

    #[test]
    fn the_square_is_flown_at_the_track_speed_and_closes() {
        let m = mission(TrackShape::Square, 1.0);
        let lap_s = 4.0 * TRACK_SIZE_M / TRACK_SPEED_MPS;
        assert_eq!(m.start_s(), TRACK_START_S);
        assert!((m.end_s() - (TRACK_START_S + TRACK_LAPS as f64 * lap_s)).abs() < 1e-9);
        let (p, v) = m.at(TRACK_START_S + 1.5).unwrap();
        assert_eq!((p, v), ([1.5, 0.0], [1.0, 0.0]));
        let (p, _) = m.at(TRACK_START_S + lap_s).unwrap();
        assert!(p[0].abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn the_eight_crosses_at_the_start_within_its_box_at_the_track_speed() {
        let m = mission(TrackShape::Eight, 1.0);
        let mut t = m.start_s();
        while t <= m.end_s() {
            let (p, v) = m.at(t).unwrap();
            let half = 0.5 * TRACK_SIZE_M + 1e-9;
            assert!(p[0].abs() <= half && p[1].abs() <= half, "{p:?}");
            assert!((v[0].hypot(v[1]) - TRACK_SPEED_MPS).abs() < 1e-9, "{v:?}");
            t += 0.01;
        }
        let (end, _) = m.at(m.end_s()).unwrap();
        assert!(end[0].abs() < 1e-9 && end[1].abs() < 1e-9);
    }
}
