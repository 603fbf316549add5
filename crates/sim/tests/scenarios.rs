//! The scenario catalogue as a library: every entry prepares and flies on the shipped room with
//! plain options, is scored, and refuses the controllers it cannot be flown with.

use plumbline_sim::runner::{Discard, SimConfig};
use plumbline_sim::scenario::{self, Controller, Options, ScenarioError, CATALOGUE};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::world::World;

fn room() -> SimConfig {
    SimConfig::new(
        World::shipped("room").unwrap().unwrap(),
        LidarProfile::xv11(),
        3,
    )
}

#[test]
fn every_scenario_flies_a_short_run_and_is_scored() {
    let mut names: Vec<&str> = CATALOGUE.iter().map(|e| e.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), CATALOGUE.len(), "names are unique");
    for entry in &CATALOGUE {
        assert!(std::ptr::eq(scenario::find(entry.name).unwrap(), entry));
        let mut config = room();
        let options = Options {
            duration_s: Some(6.0),
            ..Options::default()
        };
        let flight = entry
            .prepare(&options, &mut config)
            .unwrap_or_else(|e| panic!("{}: {e}", entry.name));
        let report = scenario::fly(&config, flight, &mut Discard).unwrap();
        assert!(report.outcome.sim_seconds > 5.0, "{}", entry.name);
        let onboard = entry.name != "survey";
        assert_eq!(report.onboard.is_some(), onboard, "{}", entry.name);
        assert_eq!(report.score.onboard.is_some(), onboard, "{}", entry.name);
        // Six seconds take the onboard stack off the ground and into Hold; the survey's
        // pilot is tracking from its climb on.
        if onboard {
            assert!(report.score.estimate_drift_m.is_some(), "{}", entry.name);
        } else {
            assert!(report.score.hold.is_some(), "{}", entry.name);
        }
    }
}

#[test]
fn controllers_a_scenario_cannot_fly_are_refused_with_the_one_that_can() {
    let refused = |name: &str, controller| {
        let options = Options {
            controller: Some(controller),
            ..Options::default()
        };
        match scenario::find(name).unwrap().prepare(&options, &mut room()) {
            Err(ScenarioError::Controller { instead, .. }) => instead,
            Err(e) => panic!("{name}: {e}"),
            Ok(_) => panic!("{name} flew with {controller:?}"),
        }
    };
    assert_eq!(refused("survey", Controller::Pid), None);
    assert_eq!(refused("survey", Controller::Mrac), None);
    assert_eq!(
        refused("lidar-failure", Controller::TestPilot),
        Some(Controller::Pid)
    );
    // The test pilot may hover for sensor logs; both onboard controllers fly every onboard
    // scenario.
    for (name, controller) in [
        ("hold", Controller::TestPilot),
        ("hold", Controller::Mrac),
        ("hold-people", Controller::Mrac),
        ("land-on-low-battery", Controller::Mrac),
        ("lidar-failure", Controller::Mrac),
    ] {
        let options = Options {
            controller: Some(controller),
            ..Options::default()
        };
        let prepared = scenario::find(name).unwrap().prepare(&options, &mut room());
        assert!(prepared.is_ok(), "{name} {controller:?}");
    }
}
