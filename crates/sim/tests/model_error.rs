//! Model error and the `track` scenario: each injected error changes what the true vehicle
//! needs (seen in the onboard stack's trim, which is all it can show, since the stack is not
//! told), and the PID stack follows the square.

use plumbline_core::msgs::FlightMode;
use plumbline_sim::runner::onboard_link::FlightLog;
use plumbline_sim::runner::{Recorder, SimConfig, StateSample, Status};
use plumbline_sim::scenario::{self, Controller, Options, Report, TrackShape};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::vehicle::model_error::{ModelError, Payload, WeakMotor};
use plumbline_sim::world::World;

/// Mass x1.3 and motor 1 at 80 %: the model error of the tracking target.
const HEAVY_AND_WEAK: ModelError = ModelError {
    mass_scale: 1.3,
    weak_motor: Some(WeakMotor {
        index: 0,
        factor: 0.8,
    }),
    ..ModelError::NONE
};

/// Keeps the true state samples.
#[derive(Default)]
struct States(Vec<StateSample>);

impl Recorder for States {
    fn state(&mut self, s: &StateSample) {
        self.0.push(*s);
    }
}

/// The hall, calm (no gusts, no people), seed 4.
fn calm_hall(lidar: LidarProfile) -> SimConfig {
    let mut config = SimConfig::new(World::shipped("hall").unwrap().unwrap(), lidar, 4);
    config.gusts = None;
    config.people = false;
    config
}

fn fly(
    scenario: &str,
    mut config: SimConfig,
    options: Options,
) -> (Report, FlightLog, Vec<StateSample>) {
    let flight = scenario::find(scenario)
        .unwrap()
        .prepare(&options, &mut config)
        .unwrap();
    let mut states = States::default();
    let report = scenario::fly(&config, flight, &mut states).unwrap();
    assert_eq!(report.outcome.status, Status::Completed, "{scenario}");
    let log = report.onboard.clone().unwrap();
    (report, log, states.0)
}

/// A calm hold of `seconds` with `error`; returns the mean motor commands over [from, to) s.
fn hold_trim(error: ModelError, seconds: f64, from: f64, to: f64) -> ([f64; 4], Vec<StateSample>) {
    let config = SimConfig {
        model_error: error,
        ..calm_hall(LidarProfile::xv11())
    };
    let options = Options {
        duration_s: Some(seconds),
        ..Options::default()
    };
    let (_, log, states) = fly("hold", config, options);
    (mean_motors(&log, from, to), states)
}

fn mean_motors(log: &FlightLog, from: f64, to: f64) -> [f64; 4] {
    let window: Vec<_> = log
        .samples
        .iter()
        .filter(|s| s.t_s >= from && s.t_s < to)
        .collect();
    assert!(!window.is_empty());
    core::array::from_fn(|i| {
        window.iter().map(|s| f64::from(s.motors[i])).sum::<f64>() / window.len() as f64
    })
}

fn mean(m: &[f64; 4]) -> f64 {
    m.iter().sum::<f64>() / 4.0
}

#[test]
fn mass_scale_raises_the_hover_throttle_by_the_root_of_the_scale() {
    let (nominal, _) = hold_trim(ModelError::NONE, 12.0, 6.0, 12.0);
    let heavy_error = ModelError {
        mass_scale: 1.3,
        ..ModelError::NONE
    };
    let (heavy, _) = hold_trim(heavy_error, 12.0, 6.0, 12.0);
    // Thrust goes with the rotor speed squared and the command sets the speed.
    let ratio = mean(&heavy) / mean(&nominal);
    assert!(
        (ratio - 1.3f64.sqrt()).abs() < 0.03,
        "throttle ratio {ratio} (nominal {nominal:?}, heavy {heavy:?})"
    );
}

#[test]
fn a_weak_motor_and_an_offset_centre_of_gravity_are_trimmed_out() {
    let (nominal, _) = hold_trim(ModelError::NONE, 12.0, 6.0, 12.0);
    let weak_error = ModelError {
        weak_motor: Some(WeakMotor {
            index: 0,
            factor: 0.8,
        }),
        ..ModelError::NONE
    };
    let (weak, _) = hold_trim(weak_error, 12.0, 6.0, 12.0);
    // Rotor 1 must spin 1/sqrt(0.8) = 1.118 times as fast as the others for the same thrust;
    // its diagonal partner (rotor 3) has the same spin, so yaw needs no help from the others.
    let lift = |m: &[f64; 4], i: usize| m[i] / mean(m);
    assert!(lift(&nominal, 0) < 1.02, "{nominal:?}");
    assert!(lift(&weak, 0) > 1.06, "weak motor 1 commands {weak:?}");
    // Centre of gravity 3 cm forward: the front rotors (1 and 4) carry more.
    let forward = ModelError {
        cg_offset_m: [0.03, 0.0],
        ..ModelError::NONE
    };
    let (cg, _) = hold_trim(forward, 12.0, 6.0, 12.0);
    let front_share = |m: &[f64; 4]| (m[0] + m[3]) / (m[1] + m[2]);
    assert!((front_share(&nominal) - 1.0).abs() < 0.01, "{nominal:?}");
    assert!(front_share(&cg) > 1.05, "cg forward commands {cg:?}");
}

#[test]
fn dropping_a_payload_is_a_step_in_the_throttle_and_a_jump_in_height() {
    let release_s = 10.0;
    let error = ModelError {
        payload: Some(Payload {
            mass_kg: 0.3,
            release_s,
        }),
        ..ModelError::NONE
    };
    let config = SimConfig {
        model_error: error,
        ..calm_hall(LidarProfile::xv11())
    };
    let options = Options {
        duration_s: Some(16.0),
        ..Options::default()
    };
    let (_, log, states) = fly("hold", config, options);
    let before = mean(&mean_motors(&log, 7.0, release_s));
    let after = mean(&mean_motors(&log, 13.0, 16.0));
    // 1.5 kg to 1.2 kg: the hover command falls by sqrt(1.2 / 1.5).
    let expect = (1.2f64 / 1.5).sqrt();
    assert!(
        (after / before - expect).abs() < 0.03,
        "throttle {before} -> {after}"
    );
    let height = |from: f64, to: f64| {
        states
            .iter()
            .filter(|s| s.t_s >= from && s.t_s < to)
            .map(|s| s.position.z)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let jump = height(release_s, release_s + 2.0) - height(release_s - 2.0, release_s);
    assert!(jump > 0.03, "height jumped {jump} m after the release");
}

#[test]
fn the_pid_stack_follows_the_square() {
    // The UTM-30LX: at 1 m/s the XV-11's keyframe odometry loses the lidar on this path.
    let config = calm_hall(LidarProfile::utm30lx());
    let options = Options {
        track: TrackShape::Square,
        duration_s: Some(48.0),
        ..Options::default()
    };
    let (report, _, _) = fly("track", config, options);
    let track = report.score.track.expect("the square was flown");
    let parts = report.score.track_parts.expect("the square was flown");
    // With the path's velocity and acceleration fed forward, what the controller sees (its
    // estimate from the setpoint) is 0.020-0.022 m RMS on seeds 1-15; the estimate's own
    // error from the truth (0.01-0.14 m) is most of the true error.
    assert!(parts.control.rms_m < 0.04, "{parts:?}");
    assert!(
        track.rms_m < 0.2 && track.max_m < 0.4,
        "tracking error rms {} m, max {} m",
        track.rms_m,
        track.max_m
    );
}

/// Mass x1.3 and motor 1 at 80 %: the vehicle needs 37 % more collective than the model
/// says. Both controllers take off and fly the square; the MRAC's adaptive element cancels
/// the thrust-scale error the PID's integrators cannot (a share of every commanded
/// acceleration), so the error it acts on is smaller (seeds 1-15: 0.028-0.031 m RMS against
/// the PID's 0.044-0.048 m).
#[test]
fn a_heavy_vehicle_with_a_weak_motor_flies_the_square_and_the_mrac_cancels_more() {
    let control_error = |controller| {
        let config = SimConfig {
            model_error: HEAVY_AND_WEAK,
            ..calm_hall(LidarProfile::utm30lx())
        };
        let options = Options {
            controller: Some(controller),
            ..Options::default()
        };
        let (report, _, _) = fly("track", config, options);
        report
            .score
            .track_parts
            .expect("the square was flown")
            .control
            .rms_m
    };
    let pid = control_error(Controller::Pid);
    let mrac = control_error(Controller::Mrac);
    assert!(pid < 0.08, "pid {pid}");
    assert!(mrac < 0.8 * pid, "pid {pid}, mrac {mrac}");
}

/// Seed 27 of the default hall (gusts, the person walking), mass x1.3 and motor 1 at 80 %: the
/// PID's take-off used to end, by the estimate, at 0.95 m while the vehicle still sat on the
/// floor (the climb integral waited for the estimate to leave the ground, the IMU-only height
/// drifted up at the climb rate asked for, and the sonar's "too close" was thrown away), and
/// the square was "flown" on the floor. The vehicle must be where the take-off says it is.
#[test]
fn a_heavy_vehicle_with_a_weak_motor_is_in_the_air_when_its_take_off_ends() {
    let config = SimConfig {
        model_error: HEAVY_AND_WEAK,
        ..SimConfig::new(
            World::shipped("hall").unwrap().unwrap(),
            LidarProfile::utm30lx(),
            27,
        )
    };
    let options = Options {
        controller: Some(Controller::Pid),
        ..Options::default()
    };
    let (report, log, states) = fly("track", config, options);
    let (hold_s, _) = *log
        .modes
        .iter()
        .find(|(_, m)| *m == FlightMode::Hold)
        .expect("the take-off ended");
    let true_height = states
        .iter()
        .find(|s| s.t_s >= hold_s)
        .map(|s| s.position.z)
        .unwrap();
    assert!(
        true_height > 0.8,
        "take-off ended at {hold_s:.2} s with the vehicle {true_height:.3} m up"
    );
    let track = report.score.track.expect("the square was flown");
    assert!(track.rms_m < 0.2, "tracking error rms {} m", track.rms_m);
}

#[test]
fn the_track_is_refused_in_a_world_it_does_not_fit() {
    let mut config = SimConfig::new(
        World::shipped("room").unwrap().unwrap(),
        LidarProfile::xv11(),
        1,
    );
    let e = scenario::find("track")
        .unwrap()
        .prepare(&Options::default(), &mut config)
        .err()
        .expect("the 3 m square does not fit the 4.5 m room with its cabinet");
    assert!(e.to_string().contains("hall"), "{e}");
}
