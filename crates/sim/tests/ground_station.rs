//! The ground-station hook: what a station sees after each onboard step, that its messages reach
//! the autopilot at the next step, and that a station that sends nothing leaves the flight
//! exactly as it is without one.

use plumbline_core::flight::events::EventKind;
use plumbline_core::flight::params::ParamError;
use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{FlightMode, GroundCommand, GroundMessages};
use plumbline_sim::runner::ground::{GroundStation, Parameters, VehicleReport};
use plumbline_sim::runner::onboard_link::{
    autopilot_for, FlightLog, OnboardLink, Script, XV11_BEAMS,
};
use plumbline_sim::runner::{run, Discard, Pilot, SimConfig};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::world::World;
use std::cell::RefCell;
use std::rc::Rc;

/// What a station saw, step by step.
#[derive(Default)]
struct Seen {
    times: Vec<f64>,
    modes: Vec<FlightMode>,
    mode_events: Vec<(f64, FlightMode)>,
    scans: usize,
    sonars: usize,
    events_missed: u32,
}

/// A station that watches and, from `kill_at_s` on, sends flight termination once.
struct Watcher {
    seen: Rc<RefCell<Seen>>,
    kill_at_s: Option<f64>,
}

impl GroundStation for Watcher {
    fn exchange(&mut self, v: &VehicleReport<'_>, _: &mut Parameters<'_>) -> GroundMessages {
        let mut seen = self.seen.borrow_mut();
        seen.times.push(v.t_s);
        seen.modes.push(v.outputs.mode);
        seen.scans += usize::from(v.scan.is_some_and(|s| !s.is_empty()));
        seen.sonars += usize::from(v.sonar.is_some());
        seen.events_missed += v.events_missed;
        for e in v.events {
            if let EventKind::ModeChange { to, .. } = e.kind {
                seen.mode_events.push((e.t_s, to));
            }
        }
        let command = match self.kill_at_s {
            Some(t) if v.t_s >= t => {
                self.kill_at_s = None;
                Some(GroundCommand::Terminate)
            }
            _ => None,
        };
        GroundMessages {
            command,
            ..GroundMessages::default()
        }
    }
}

fn config(duration_s: f64) -> SimConfig {
    let mut c = SimConfig::new(
        World::shipped("room").unwrap().unwrap(),
        LidarProfile::xv11(),
        5,
    );
    c.people = false;
    c.max_duration_s = duration_s;
    c
}

fn fly(c: &SimConfig, station: Option<Watcher>) -> FlightLog {
    let (mut link, log) = OnboardLink::<XV11_BEAMS>::new(
        &c.lidar,
        OdometryConfig::default(),
        autopilot_for(&c.vehicle),
        Script::arm_at(0.5),
    )
    .unwrap();
    if let Some(s) = station {
        link.link_ground_station(Box::new(s));
    }
    run(c, Pilot::Onboard(Box::new(link)), &mut Discard).unwrap();
    let log = log.borrow().clone();
    log
}

#[test]
fn a_silent_station_sees_every_step_and_changes_nothing() {
    let c = config(6.0);
    let alone = fly(&c, None);
    let seen = Rc::new(RefCell::new(Seen::default()));
    let watched = fly(
        &c,
        Some(Watcher {
            seen: seen.clone(),
            kill_at_s: None,
        }),
    );
    assert_eq!(
        alone, watched,
        "a station that sends nothing changed the flight"
    );
    let seen = seen.borrow();
    // Every onboard step (500 Hz) is reported once, in order.
    assert!(
        (2995..=3001).contains(&seen.times.len()),
        "{}",
        seen.times.len()
    );
    assert!(seen.times.windows(2).all(|w| w[1] > w[0]));
    // The reported modes are the log's, and the logged mode changes arrive as events.
    assert_eq!(seen.modes.last(), Some(&watched.final_mode()));
    let changes: Vec<FlightMode> = watched.modes.iter().skip(1).map(|m| m.1).collect();
    let events: Vec<FlightMode> = seen.mode_events.iter().map(|e| e.1).collect();
    assert_eq!(events, changes, "mode-change events vs the log");
    assert_eq!(seen.events_missed, 0);
    // About 4 XV-11 revolutions a second for 6 s; sonar at its own rate.
    assert!((20..=31).contains(&seen.scans), "{}", seen.scans);
    assert!(seen.sonars > 50, "{}", seen.sonars);
}

#[test]
fn a_kill_from_the_ground_stops_the_motors_at_the_next_step() {
    let c = config(6.0);
    let seen = Rc::new(RefCell::new(Seen::default()));
    let log = fly(
        &c,
        Some(Watcher {
            seen: seen.clone(),
            kill_at_s: Some(4.0),
        }),
    );
    let seen = seen.borrow();
    let sent = seen.times.iter().position(|&t| t >= 4.0).unwrap();
    // Sent after step `sent`: the autopilot acts on it at step `sent + 1`.
    assert_ne!(
        seen.modes[sent],
        FlightMode::Killed,
        "killed before it was sent"
    );
    assert_eq!(seen.modes[sent + 1], FlightMode::Killed);
    assert_eq!(log.final_mode(), FlightMode::Killed);
    let killed_at = log.modes.last().unwrap().0;
    assert_eq!(killed_at, seen.times[sent + 1]);
    let motors_after: Vec<_> = log.samples.iter().filter(|s| s.t_s > killed_at).collect();
    assert!(!motors_after.is_empty());
    assert!(motors_after.iter().all(|s| s.motors == [0.0; 4]));
}

/// Parameter 0's value before a set, and what the set returned.
type SetResult = (Option<f32>, Result<f32, ParamError>);

/// A station that sets parameter 0 once in range and once out of it, keeping what it saw.
struct Tuner {
    results: Rc<RefCell<Vec<SetResult>>>,
}

impl GroundStation for Tuner {
    fn exchange(&mut self, _: &VehicleReport<'_>, p: &mut Parameters<'_>) -> GroundMessages {
        let mut results = self.results.borrow_mut();
        if results.is_empty() {
            let info = p.info(0).unwrap();
            let before = p.get(0);
            let inside = (info.min + info.max) / 2.0;
            results.push((before, p.set(0, inside)));
            results.push((p.get(0), p.set(0, info.max * 2.0 + 1.0)));
            results.push((p.get(0), p.set(0, f32::NAN)));
            results.push((p.get(0), p.set(p.count(), 1.0)));
        }
        GroundMessages::default()
    }
}

#[test]
fn a_station_reads_and_sets_bounded_parameters() {
    let c = config(1.0);
    let results = Rc::new(RefCell::new(Vec::new()));
    let (mut link, _) = OnboardLink::<XV11_BEAMS>::new(
        &c.lidar,
        OdometryConfig::default(),
        autopilot_for(&c.vehicle),
        Script::default(),
    )
    .unwrap();
    link.link_ground_station(Box::new(Tuner {
        results: results.clone(),
    }));
    run(&c, Pilot::Onboard(Box::new(link)), &mut Discard).unwrap();
    let r = results.borrow();
    let inside = r[1].0.unwrap();
    assert_eq!(r[0].1, Ok(inside), "an in-range value is applied: {r:?}");
    assert!(
        matches!(r[1].1, Err(ParamError::OutOfRange { .. })),
        "{r:?}"
    );
    assert_eq!(r[2].1, Err(ParamError::NotFinite));
    assert_eq!(r[3].1, Err(ParamError::Unknown));
    // Refused values leave the one in force.
    assert_eq!((r[2].0, r[3].0), (Some(inside), Some(inside)));
}
