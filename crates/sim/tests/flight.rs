//! Whole flights through the runner: the test pilot flying shipped worlds, reproducibility,
//! disturbances, bad input.

use plumbline_core::msgs::{ImuSample, SonarSample};
use plumbline_sim::disturb::Push;
use plumbline_sim::math::Vec3;
use plumbline_sim::runner::plan::{Plan, PlanLimits};
use plumbline_sim::runner::{
    run, Discard, Outcome, Pilot, Recorder, SetupError, SimConfig, Status, TruthPose,
};
use plumbline_sim::scenario::{fly, Flight};
use plumbline_sim::sensors::lidar::{LidarProfile, LidarScan};
use plumbline_sim::vehicle::VehicleParams;
use plumbline_sim::world::World;

fn config(world: &str, seed: u64) -> SimConfig {
    SimConfig::new(
        World::shipped(world).unwrap().unwrap(),
        LidarProfile::xv11(),
        seed,
    )
}

fn hold(c: &SimConfig, seconds: f64) -> Pilot<'static> {
    Pilot::Test(Plan::hold(&c.world, PlanLimits::default(), seconds))
}

/// Keeps every output as text, the way the files would hold it.
#[derive(Default)]
struct Transcript {
    lines: Vec<String>,
    scans: Vec<(LidarScan, TruthPose)>,
}

impl Recorder for Transcript {
    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        self.lines
            .push(format!("scan {:?} {:?}", scan.ranges_m, truth));
        self.scans.push((scan.clone(), *truth));
    }
    fn imu(&mut self, s: &ImuSample) {
        self.lines.push(format!("imu {s:?}"));
    }
    fn sonar(&mut self, s: &SonarSample) {
        self.lines.push(format!("sonar {s:?}"));
    }
}

#[test]
fn survey_of_the_office_completes_clear_of_the_walls() {
    let c = config("office", 7);
    let plan = Plan::survey(&c.world, PlanLimits::default());
    let mut rec = Transcript::default();
    let report = fly(&c, Flight::test_pilot(plan.clone(), &c), &mut rec).unwrap();
    let out = report.outcome;
    assert_eq!(out.status, Status::Completed, "{out:?}");
    assert!(out.min_clearance_m > c.vehicle.radius_m, "{out:?}");
    let tracking = report.score.hold.unwrap();
    assert!(tracking.rms_m < 0.1, "{tracking:?}");
    assert!(out.distance_flown_m > 45.0, "{out:?}");
    // XV-11 revolutions every 250 ms for the whole flight.
    let expect = (out.sim_seconds / 0.25).floor() as u64;
    assert!(
        out.scans + 1 >= expect && out.scans <= expect,
        "{} scans in {} s",
        out.scans,
        out.sim_seconds
    );
    // The truth of each scan is its first beam's time and the vehicle really flew the path.
    let far = rec
        .scans
        .iter()
        .map(|(_, t)| t.position.x)
        .fold(0.0, f64::max);
    assert!(far > 17.0, "reached the east end: {far}");
    for (scan, truth) in &rec.scans {
        assert_eq!(scan.stamp_s, truth.t_s);
    }
    let valid: usize = rec
        .scans
        .iter()
        .map(|(s, _)| s.valid.iter().filter(|&&v| v).count())
        .sum();
    assert!(
        valid as f64 > 0.5 * (rec.scans.len() * 360) as f64,
        "most beams return in an office"
    );
    // Seed 000 Fig. 12 shape over a whole flight.
    let [m, e, a] = out.energy.fractions();
    assert!(
        (0.93..0.97).contains(&m) && (0.03..0.05).contains(&e) && (0.005..0.02).contains(&a),
        "{m} {e} {a}"
    );
    assert!(out.battery_end_v < out.battery_min_v + 1.5 && out.battery_end_soc < 1.0);
}

#[test]
fn same_seed_same_outputs_other_seed_differs() {
    let flight = |seed| {
        let c = config("room", seed);
        let mut rec = Transcript::default();
        let out = run(&c, hold(&c, 3.0), &mut rec).unwrap();
        (format!("{out:?}"), rec.lines)
    };
    let (a, b, other) = (flight(3), flight(3), flight(4));
    assert!(a.1.len() > 1000);
    assert_eq!(a, b);
    assert_ne!(a.1, other.1);
}

#[test]
fn hover_hold_is_tight_and_a_push_moves_the_vehicle() {
    let quiet = SimConfig {
        gusts: None,
        ..config("room", 1)
    };
    let hover = |c: &SimConfig| {
        let plan = Plan::hold(&c.world, PlanLimits::default(), 10.0);
        fly(c, Flight::test_pilot(plan, c), &mut Discard).unwrap()
    };
    let calm = hover(&quiet);
    assert_eq!(calm.outcome.status, Status::Completed);
    // Motor mismatch (2 %) tilts the take-off a little until the integrator catches it.
    assert!(calm.score.hold.unwrap().max_m < 0.1, "{calm:?}");
    let pushed_cfg = SimConfig {
        pushes: vec![Push {
            start_s: 8.0,
            duration_s: 0.5,
            force_n: Vec3::new(0.0, 3.0, 0.0),
        }],
        ..quiet.clone()
    };
    let pushed = hover(&pushed_cfg);
    assert!(pushed.score.hold.unwrap().max_m > 0.25, "{pushed:?}");
    assert_eq!(
        pushed.outcome.status,
        Status::Completed,
        "the pilot recovers"
    );
    let (calm, g) = (calm.outcome, hover(&config("room", 1)).outcome);
    // Gusts shake the vehicle about: it travels further holding the same point. (Its largest
    // error is the take-off transient of the motor mismatch, in calm air as in gusts.)
    assert!(
        g.distance_flown_m > calm.distance_flown_m + 0.02,
        "gusts disturb the hold: {g:?} vs {calm:?}"
    );
}

#[test]
fn people_walking_through_the_room_show_up_in_the_scans() {
    let scans = |people| {
        let c = SimConfig {
            people,
            ..config("room", 2)
        };
        let mut rec = Transcript::default();
        run(&c, hold(&c, 8.0), &mut rec).unwrap();
        rec.scans
    };
    let (with, without) = (scans(true), scans(false));
    assert_eq!(with.len(), without.len());
    // Same seed, same noise: a return that is new or shorter was blocked by a person.
    let mut shortened = 0;
    for ((a, _), (b, _)) in with.iter().zip(&without) {
        for k in 0..a.ranges_m.len() {
            if a.valid[k] && (!b.valid[k] || a.ranges_m[k] + 0.3 < b.ranges_m[k]) {
                shortened += 1;
            }
        }
    }
    assert!(shortened > 300, "{shortened}");
}

#[test]
fn bad_setups_are_errors_and_blowups_are_a_status() {
    let c = config("room", 1);
    let inside = World::parse("start 3 3 0\noutline 0 0 6 0 6 6 0 6\nbox 2 2 4 4\n").unwrap();
    let e = run(
        &SimConfig {
            world: inside,
            ..c.clone()
        },
        hold(&c, 1.0),
        &mut Discard,
    )
    .unwrap_err();
    assert!(
        matches!(&e, SetupError::World(w) if w.reason.contains("inside a solid block")),
        "{e}"
    );
    let heavy = VehicleParams {
        mass_kg: -1.0,
        ..VehicleParams::f450()
    };
    let e = run(
        &SimConfig {
            vehicle: heavy,
            ..c.clone()
        },
        hold(&c, 1.0),
        &mut Discard,
    )
    .unwrap_err();
    assert!(e.to_string().contains("mass_kg"), "{e}");
    // A feather-light airframe makes the fixed-step integration blow up: reported, not a panic.
    let twitchy = VehicleParams {
        inertia_kgm2: [1e-9, 1e-9, 1e-9],
        ..VehicleParams::f450()
    };
    let out: Outcome = run(
        &SimConfig {
            vehicle: twitchy,
            ..c.clone()
        },
        hold(&c, 5.0),
        &mut Discard,
    )
    .unwrap();
    assert!(
        matches!(out.status, Status::Diverged { t_s } if t_s > 0.0 && t_s < 5.0),
        "{out:?}"
    );
}

#[test]
fn a_small_battery_runs_low_and_its_voltage_sags() {
    let mut c = config("room", 1);
    c.vehicle.battery.capacity_ah = 0.12;
    let out = run(&c, hold(&c, 60.0), &mut Discard).unwrap();
    let low = out
        .battery_low_at_s
        .expect("a 120 mAh pack cannot hover for a minute");
    assert!(low > 5.0, "{out:?}");
    assert!(out.battery_min_v < 3.5 * 3.0, "{out:?}");
}
