//! Closed-loop flight: the onboard stack of `plumbline-core` (lidar odometry, EKF, cascaded PID,
//! mixer, modes and failsafes) flying the simulated vehicle through the runner's
//! `FlightSoftware` interface. Seed 000 Fig. 8-9: ICL displacement drives the hold.

use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{FailsafeReason, FlightMode, PilotInput};
use plumbline_sim::disturb::Push;
use plumbline_sim::math::Vec3;
use plumbline_sim::runner::onboard_link::{
    autopilot_for, FlightLog, OnboardLink, Script, XV11_BEAMS,
};
use plumbline_sim::runner::{run, Pilot, Recorder, SimConfig, StateSample, Status};
use plumbline_sim::scenario::score::{self, horizontal_error};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::world::World;

/// What the test wants to see after the run: the stack's own log and the ground truth.
struct Log {
    onboard: FlightLog,
    truth: Vec<StateSample>,
}

#[derive(Default)]
struct Truth(Vec<StateSample>);

impl Recorder for Truth {
    fn state(&mut self, s: &StateSample) {
        self.0.push(*s);
    }
}

fn fly(config: &SimConfig, arm: &[(f64, bool)], lidar_dies_at_s: Option<f64>) -> (Status, Log) {
    let script = Script {
        radio: arm
            .iter()
            .map(|&(t, arm)| {
                let radio = PilotInput {
                    arm,
                    ..PilotInput::default()
                };
                (t, radio)
            })
            .collect(),
        lidar_dies_at_s,
        mission: None,
    };
    let (link, log) = OnboardLink::<XV11_BEAMS>::new(
        &config.lidar,
        OdometryConfig::default(),
        autopilot_for(&config.vehicle),
        script,
    )
    .unwrap();
    let mut truth = Truth::default();
    let out = run(config, Pilot::Onboard(Box::new(link)), &mut truth).unwrap();
    let onboard = log.borrow().clone();
    (
        out.status,
        Log {
            onboard,
            truth: truth.0,
        },
    )
}

fn room(seed: u64) -> SimConfig {
    let mut c = SimConfig::new(
        World::shipped("room").unwrap().unwrap(),
        LidarProfile::xv11(),
        seed,
    );
    c.people = false;
    c
}

/// The room with seed 000's external force: 2 N along x for 1 s from `push_s`.
fn pushed_room(seed: u64, push_s: f64, duration_s: f64) -> SimConfig {
    let mut c = room(seed);
    c.pushes.push(Push {
        start_s: push_s,
        duration_s: 1.0,
        force_n: Vec3::new(2.0, 0.0, 0.0),
    });
    c.max_duration_s = duration_s;
    c
}

/// Hold error from the start over a time window, (rms, max).
fn hold_error(log: &Log, start: [f64; 2], from_s: f64, to_s: f64) -> (f64, f64) {
    let e = score::hold_error(&log.truth, start, |t| t >= from_s && t < to_s)
        .expect("truth in the window");
    (e.rms_m, e.max_m)
}

#[test]
fn holds_over_the_start_through_a_push_and_lands() {
    let c = pushed_room(11, 15.0, 34.0);
    let start = [c.world.start[0], c.world.start[1]];
    let (status, log) = fly(&c, &[(0.5, true), (25.0, false)], None);
    println!("modes {:?}", log.onboard.modes);
    assert_eq!(status, Status::Completed);
    let (rms, max) = hold_error(&log, start, 8.0, 15.0);
    let err = |s: &StateSample| horizontal_error(s.position, start);
    let after_push = || log.truth.iter().filter(|s| s.t_s >= 16.0 && s.t_s < 25.0);
    // The summary's recovery_s: from the end of the push until back within 5 cm.
    let recovery_s = after_push().find(|s| err(s) <= 0.05).map(|s| s.t_s - 16.0);
    // Stricter: from the end of the push until it stays within 5 cm for good.
    let settled_s = after_push()
        .rev()
        .find(|s| err(s) > 0.05)
        .map_or(0.0, |s| s.t_s - 16.0);
    let (rms_after, _) = hold_error(&log, start, 20.0, 25.0);
    println!(
        "hold rms {rms:.4} m, max {max:.4} m; push: back within 5 cm after {recovery_s:?} s, \
         stays within after {settled_s:.2} s, rms 4-9 s after {rms_after:.4} m"
    );
    assert!(rms < 0.05, "rms {rms}");
    assert!(
        recovery_s.is_some_and(|s| s <= 3.0),
        "recovery {recovery_s:?}"
    );
    // 4-9 s after the push the vehicle is back on station (1.2 cm RMS on this seed): the scan
    // match is fused at mid-revolution, so the estimate keeps up with the post-push swing.
    assert!(rms_after < 0.05, "rms after the push {rms_after}");
    let modes: Vec<FlightMode> = log.onboard.modes.iter().map(|m| m.1).collect();
    use FlightMode::*;
    assert_eq!(modes, vec![Disarmed, Takeoff, Hold, Land, Disarmed]);
}

/// Seed 58 of the hold takes a keyframe in the fast swing after the push. Without the beams
/// de-skewed to mid-revolution, that keyframe keeps the revolution's smear (0.2 m of travel over
/// the XV-11's turn) and the estimate stays 10 cm off for the rest of the flight; with them it
/// holds like every other seed.
#[test]
fn a_keyframe_taken_in_the_swing_after_a_push_does_not_shift_the_hold() {
    let c = pushed_room(58, 20.0, 45.0);
    let start = [c.world.start[0], c.world.start[1]];
    let (status, log) = fly(&c, &[(0.5, true)], None);
    assert_eq!(status, Status::Completed);
    let (rms, max) = hold_error(&log, start, 25.0, 45.0);
    println!("seed 58, 5-25 s after the push: rms {rms:.4} m, max {max:.4} m");
    assert!(rms < 0.04, "rms {rms}");
}

/// The lidar-failure scenario over twenty seeds: the lidar stops 10 s into the flight, "lidar
/// lost" is raised, the vehicle holds on the IMU for a while, then lands. The room's walls are
/// 1 m from the start (0.65 m from the vehicle's rim), so the IMU-only flight must stay close.
/// Seeds 300-319 were not used in tuning (mean 0.21 m, worst 0.51 m).
#[test]
fn twenty_seeds_of_lidar_failure_land_near_where_the_lidar_stopped() {
    const DIES_AT_S: f64 = 10.0;
    let (mut failures, mut strays) = (Vec::new(), Vec::new());
    for seed in 300..320 {
        let mut c = room(seed);
        c.max_duration_s = 15.0;
        let (status, log) = fly(&c, &[(0.5, true)], Some(DIES_AT_S));
        let at = |t: f64| log.truth.iter().find(|s| s.t_s >= t).or(log.truth.last());
        let (Some(stop), Some(end)) = (at(DIES_AT_S), log.truth.last()) else {
            failures.push((seed, "no truth".to_string()));
            continue;
        };
        let stray = (end.position.x - stop.position.x).hypot(end.position.y - stop.position.y);
        strays.push(stray);
        let landed = log.onboard.final_mode() == FlightMode::Disarmed;
        let reason = log.onboard.failsafe == Some(FailsafeReason::LidarLost);
        if status != Status::Completed || !landed || !reason || stray > 0.6 {
            failures.push((
                seed,
                format!("{status:?} landed {landed} stray {stray:.2} m"),
            ));
        }
    }
    let mean = strays.iter().sum::<f64>() / strays.len().max(1) as f64;
    let worst = strays.iter().copied().fold(0.0, f64::max);
    println!("landed {mean:.3} m from where the lidar stopped on average, worst {worst:.3} m");
    assert!(failures.is_empty(), "{failures:?}");
    assert!(mean < 0.3, "mean stray {mean}");
}

/// A hundred seeds of the hold with seed 000's push: none may crash, and the hold error before
/// the push must average well within the 5 cm target (1.65 cm measured).
#[test]
fn a_hundred_seeds_of_hold_and_push_do_not_crash() {
    let (mut crashes, mut rms_sum, mut flown) = (Vec::new(), 0.0, 0);
    for seed in 100..200 {
        let c = pushed_room(seed, 20.0, 30.0);
        let start = [c.world.start[0], c.world.start[1]];
        let (status, log) = fly(&c, &[(0.5, true)], None);
        if status != Status::Completed {
            crashes.push((seed, status));
            continue;
        }
        rms_sum += hold_error(&log, start, 8.0, 20.0).0;
        flown += 1;
    }
    let mean_rms = rms_sum / flown.max(1) as f64;
    println!("mean hold rms over {flown} seeds: {mean_rms:.4} m");
    assert!(crashes.is_empty(), "{crashes:?}");
    assert!(mean_rms < 0.03, "{mean_rms}");
}
