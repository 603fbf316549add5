//! The pilot's radio flown through the whole loop: the onboard stack of `plumbline-core` in
//! manual mode, the simulated vehicle, and the motion judged in world truth. A stick that flies
//! the wrong way is a crash waiting for the first safety pilot, so each stick is checked against
//! the same flight with the stick centred: roll right moves right, pitch forward moves forward,
//! yaw right turns clockwise seen from above, throttle up climbs. The kill switch and a manual
//! takeover from the autonomous hold are flown too.

use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{FlightMode, MotorCommands, PilotInput};
use plumbline_sim::runner::onboard_link::{
    autopilot_for, FlightLog, OnboardLink, Script, XV11_BEAMS,
};
use plumbline_sim::runner::{
    run, FlightSoftware, Pilot, Recorder, SensorFrame, SimConfig, StateSample, Status,
};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::world::World;
use std::cell::RefCell;
use std::rc::Rc;

/// An 8 m square room with the start in the middle, turned 0.5 rad so that "right" and
/// "forward" are not the world axes: a stick mapped to the wrong axis cannot pass by luck.
const OPEN_ROOM: &str = "name open
ceiling 4
start 4 4 0.5
altitude 1
outline 0 0 8 0 8 8 0 8
box 0.5 0.5 1.5 1.5
";

/// The onboard stack, with every motor command it returns kept (the flight log samples only
/// at 50 Hz; the kill switch must act at the very next control step).
struct Watched {
    link: OnboardLink<XV11_BEAMS>,
    commands: Rc<RefCell<Vec<(f64, MotorCommands)>>>,
}

impl FlightSoftware for Watched {
    fn rate_hz(&self) -> f64 {
        self.link.rate_hz()
    }
    fn step(&mut self, sensors: &SensorFrame<'_>, dt_s: f64) -> MotorCommands {
        let m = self.link.step(sensors, dt_s);
        self.commands.borrow_mut().push((sensors.t_s, m));
        m
    }
}

#[derive(Default)]
struct Truth(Vec<StateSample>);

impl Recorder for Truth {
    fn state(&mut self, s: &StateSample) {
        self.0.push(*s);
    }
}

struct Flown {
    status: Status,
    truth: Vec<StateSample>,
    log: FlightLog,
    commands: Vec<(f64, MotorCommands)>,
}

impl Flown {
    /// The true state at the first sample at or after `t_s`.
    fn at(&self, t_s: f64) -> &StateSample {
        self.truth
            .iter()
            .find(|s| s.t_s >= t_s)
            .unwrap_or_else(|| panic!("no truth at {t_s} s ({:?})", self.status))
    }
}

fn fly(config: &SimConfig, script: Script) -> Flown {
    let (link, log) = OnboardLink::<XV11_BEAMS>::new(
        &config.lidar,
        OdometryConfig::default(),
        autopilot_for(&config.vehicle),
        script,
    )
    .unwrap();
    let commands = Rc::new(RefCell::new(Vec::new()));
    let watched = Watched {
        link,
        commands: commands.clone(),
    };
    let mut truth = Truth::default();
    let status = run(config, Pilot::Onboard(Box::new(watched)), &mut truth)
        .unwrap()
        .status;
    let log = log.borrow().clone();
    let commands = commands.borrow().clone();
    Flown {
        status,
        truth: truth.0,
        log,
        commands,
    }
}

/// Still air and no people, so that the only difference between two flights is the stick.
fn calm(world: World, seconds: f64) -> SimConfig {
    let mut c = SimConfig::new(world, LidarProfile::xv11(), 5);
    c.gusts = None;
    c.people = false;
    c.max_duration_s = seconds;
    c
}

fn open_room(seconds: f64) -> SimConfig {
    calm(World::parse(OPEN_ROOM).unwrap(), seconds)
}

/// Collective that holds the vehicle up in manual, from the airframe.
fn hover(c: &SimConfig) -> f32 {
    autopilot_for(&c.vehicle).cascade.hover_collective
}

/// Armed in manual at 0.5 s, a climb on the throttle and a brake as long, then the throttle
/// at hover; `stick` is held from 3.0 s to `3.0 + stick_s` and then centred.
fn manual_flight(c: &SimConfig, stick: PilotInput, stick_s: f64) -> Script {
    let hover = hover(c);
    let radio = |throttle_norm: f32| PilotInput {
        arm: true,
        manual: true,
        throttle_norm,
        ..PilotInput::default()
    };
    // The stick's throttle is relative to hover.
    let with_stick = PilotInput {
        arm: true,
        manual: true,
        throttle_norm: hover + stick.throttle_norm,
        ..stick
    };
    Script {
        radio: vec![
            (0.5, radio(hover + 0.03)),
            (1.5, radio(hover - 0.03)),
            (2.5, radio(hover)),
            (3.0, with_stick),
            (3.0 + stick_s, radio(hover)),
        ],
        lidar_dies_at_s: None,
        mission: None,
    }
}

/// Where the vehicle went between 3 s (the stick) and `end_s`, in the start's heading frame:
/// (forward, left, up) in metres.
fn moved(f: &Flown, c: &SimConfig, end_s: f64) -> [f64; 3] {
    let (a, b) = (f.at(3.0).position, f.at(end_s).position);
    let (sin, cos) = c.world.start[2].sin_cos();
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    [cos * dx + sin * dy, -sin * dx + cos * dy, b.z - a.z]
}

/// The same manual flight with the stick centred and with `stick`; returns how much further
/// (forward, left, up) the stick took the vehicle by `end_s`, and both flights.
fn against_centred(stick: PilotInput, stick_s: f64, end_s: f64) -> ([f64; 3], Flown, Flown) {
    let c = open_room(end_s + 0.5);
    let centred = fly(&c, manual_flight(&c, PilotInput::default(), stick_s));
    let flown = fly(&c, manual_flight(&c, stick, stick_s));
    for f in [&centred, &flown] {
        assert_eq!(f.status, Status::Completed, "{:?}", f.log.modes);
        assert_eq!(f.log.final_mode(), FlightMode::Manual);
        assert!(f.at(3.0).position.z > 0.3, "airborne before the stick");
    }
    let (a, b) = (moved(&centred, &c, end_s), moved(&flown, &c, end_s));
    ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], centred, flown)
}

#[test]
fn roll_right_banks_right_and_moves_the_vehicle_right() {
    let stick = PilotInput {
        roll_norm: 0.3,
        ..PilotInput::default()
    };
    let ([forward, left, _], _, flown) = against_centred(stick, 0.2, 5.0);
    println!("roll right: {forward:.3} m forward, {left:.3} m left");
    // FLU: right is -y. The bank itself is a positive roll (right side down).
    assert!(left < -0.5, "{left}");
    assert!(forward.abs() < 0.5 * left.abs(), "{forward}");
    let roll = flown.at(3.2).euler[0];
    assert!(roll > 0.02, "{roll}");
}

#[test]
fn pitch_forward_moves_the_vehicle_forward() {
    let stick = PilotInput {
        pitch_norm: 0.3,
        ..PilotInput::default()
    };
    let ([forward, left, _], _, _) = against_centred(stick, 0.2, 5.0);
    println!("pitch forward: {forward:.3} m forward, {left:.3} m left");
    assert!(forward > 0.5, "{forward}");
    assert!(left.abs() < 0.5 * forward, "{left}");
}

#[test]
fn yaw_right_turns_clockwise_seen_from_above() {
    let stick = PilotInput {
        yaw_norm: 0.5,
        ..PilotInput::default()
    };
    let (_, centred, flown) = against_centred(stick, 0.5, 4.5);
    let turn = |f: &Flown| {
        let (a, b) = (f.at(3.0).euler[2], f.at(4.5).euler[2]);
        let d = b - a;
        d.sin().atan2(d.cos())
    };
    let (base, turned) = (turn(&centred), turn(&flown));
    println!("yaw right: turned {turned:.3} rad, centred {base:.3} rad");
    // Clockwise from above is a negative yaw change about world z (up).
    assert!(turned - base < -0.1, "{turned} vs {base}");
}

#[test]
fn throttle_up_climbs() {
    let stick = PilotInput {
        throttle_norm: 0.1,
        ..PilotInput::default()
    };
    let ([_, _, up], _, _) = against_centred(stick, 0.5, 4.0);
    println!("throttle up: {up:.3} m higher");
    assert!(up > 0.2, "{up}");
}

/// The shipped room, armed at 0.5 s: the autopilot takes off and holds 1 m over the start.
fn autonomous_hold(seconds: f64) -> (SimConfig, Vec<(f64, PilotInput)>) {
    let c = calm(World::shipped("room").unwrap().unwrap(), seconds);
    (c, Script::arm_at(0.5).radio)
}

#[test]
fn the_kill_switch_stops_the_motors_at_the_next_step_and_the_vehicle_falls() {
    const KILL_S: f64 = 8.0;
    let (c, mut radio) = autonomous_hold(12.0);
    let armed = radio[0].1;
    radio.push((
        KILL_S,
        PilotInput {
            kill: true,
            ..armed
        },
    ));
    let f = fly(
        &c,
        Script {
            radio,
            lidar_dies_at_s: None,
            mission: None,
        },
    );
    let held = f.at(KILL_S - 0.01).position.z;
    assert!(held > 0.7, "holding before the kill: {held}");
    let after: Vec<_> = f.commands.iter().filter(|(t, _)| *t >= KILL_S).collect();
    assert!(!after.is_empty());
    // SAFETY: not one step with the motors running once the switch is on.
    for (t, m) in &after {
        assert_eq!(*m, MotorCommands::STOPPED, "motors running at {t} s");
    }
    let before = f.commands.iter().rev().find(|(t, _)| *t < KILL_S).unwrap();
    assert!(
        before.1.throttle_norm.iter().all(|m| *m > 0.1),
        "{before:?}"
    );
    assert_eq!(f.log.final_mode(), FlightMode::Killed);
    // It falls: the floor ends the flight, from 1 m faster than a landing may be.
    let fell = f.truth.last().unwrap().position.z;
    assert!(fell < 0.5 * held, "{fell}");
    assert!(
        matches!(&f.status, Status::Crashed { t_s, reason } if reason.contains("floor") && *t_s > KILL_S),
        "{:?}",
        f.status
    );
}

/// Hold until 8 s, then manual with the throttle at hover and the pitch stick pushed
/// forward by `pitch_norm` from 8.2 s to 8.5 s, and the switch back to the autopilot at 9.5 s.
fn takeover(pitch_norm: f32) -> (SimConfig, Flown) {
    let (c, mut radio) = autonomous_hold(16.0);
    let armed = radio[0].1;
    let manual = |pitch_norm: f32| PilotInput {
        manual: true,
        throttle_norm: hover(&c),
        pitch_norm,
        ..armed
    };
    radio.extend([
        (8.0, manual(0.0)),
        (8.2, manual(pitch_norm)),
        (8.5, manual(0.0)),
        (9.5, armed),
    ]);
    let f = fly(
        &c,
        Script {
            radio,
            lidar_dies_at_s: None,
            mission: None,
        },
    );
    (c, f)
}

#[test]
fn a_manual_takeover_flies_the_sticks_and_hands_back_to_hold() {
    let (_, centred) = takeover(0.0);
    let (c, pushed) = takeover(0.3);
    use FlightMode::*;
    for f in [&centred, &pushed] {
        assert_eq!(f.status, Status::Completed, "{:?}", f.log.modes);
        let modes: Vec<FlightMode> = f.log.modes.iter().map(|m| m.1).collect();
        assert_eq!(modes, vec![Disarmed, Takeoff, Hold, Manual, Hold]);
        let switched = f.log.modes[3].0;
        assert!((8.0..8.01).contains(&switched), "{switched}");
        let end = f.truth.last().unwrap().position;
        assert!(end.z > 0.7, "still flying after the hand-back: {end:?}");
    }
    // The room's start heading is world x: forward is +x.
    assert_eq!(c.world.start[2], 0.0);
    let forward = |f: &Flown| f.at(9.5).position.x - f.at(8.0).position.x;
    let (base, flown) = (forward(&centred), forward(&pushed));
    println!("manual: {flown:.3} m forward with the stick, {base:.3} m centred");
    assert!(flown - base > 0.1, "{flown} vs {base}");
}
