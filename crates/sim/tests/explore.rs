//! The `explore` scenario end to end: the onboard stack and its companion (SLAM, explorer,
//! guidance) fly a world they have never seen, scored against its truth. Runs are short; the
//! ten-minute flights of the targets are the benchmarks' (`scripts/explore-seeds.sh`).

use plumbline_sim::runner::companion::{ExploreEnd, Strategy};
use plumbline_sim::runner::{Recorder, SimConfig, StateSample};
use plumbline_sim::scenario::{self, Options, Report};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::world::World;

const CLOSED_ROOM: &str = include_str!("../worlds/explore/closed-room.world");
const NARROW_GAP: &str = include_str!("../worlds/explore/narrow-gap.world");
const LONG_CORRIDOR: &str = include_str!("../worlds/explore/long-corridor.world");

/// Keeps the true states.
#[derive(Default)]
struct States(Vec<StateSample>);

impl Recorder for States {
    fn state(&mut self, s: &StateSample) {
        self.0.push(*s);
    }
}

fn explore(
    world: World,
    seed: u64,
    duration_s: f64,
    strategy: Strategy,
) -> (Report, Vec<StateSample>) {
    let mut config = SimConfig::new(world, LidarProfile::xv11(), seed);
    let options = Options {
        duration_s: Some(duration_s),
        strategy,
        ..Options::default()
    };
    let flight = scenario::find("explore")
        .unwrap()
        .prepare(&options, &mut config)
        .unwrap();
    let mut states = States::default();
    let report = scenario::fly(&config, flight, &mut states).unwrap();
    (report, states.0)
}

fn shipped(name: &str) -> World {
    World::shipped(name).unwrap().unwrap()
}

#[test]
fn the_hard_worlds_parse() {
    for (name, text) in [
        ("closed-room", CLOSED_ROOM),
        ("narrow-gap", NARROW_GAP),
        ("dead-end", include_str!("../worlds/explore/dead-end.world")),
        (
            "long-corridor",
            include_str!("../worlds/explore/long-corridor.world"),
        ),
        (
            "left-doors",
            include_str!("../worlds/explore/left-doors.world"),
        ),
    ] {
        let w = World::parse(text).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(w.name, name);
        w.check_free([w.start[0], w.start[1]], 0.35, "start")
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn a_short_seeded_exploration_of_the_office_repeats_exactly_and_gets_somewhere() {
    let (a, states_a) = explore(shipped("office"), 3, 40.0, Strategy::Frontier);
    let (b, states_b) = explore(shipped("office"), 3, 40.0, Strategy::Frontier);
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.score, b.score);
    assert_eq!(states_a, states_b);
    let e = a.score.explore.as_ref().unwrap();
    // Take-off and the first half minute: the start room and the corridor around it are seen,
    // and the vehicle has moved off its take-off point without touching anything.
    assert!(e.explored_fraction > 0.1, "{e:?}");
    assert!(a.outcome.distance_flown_m > 2.0, "{:?}", a.outcome);
    assert_eq!(e.collisions, 0, "{e:?}");
}

#[test]
fn a_gap_narrower_than_the_vehicle_is_never_flown_through() {
    let world = World::parse(NARROW_GAP).unwrap();
    for strategy in [Strategy::Frontier, Strategy::WallFollow] {
        let (report, states) = explore(world.clone(), 5, 150.0, strategy);
        let e = report.score.explore.as_ref().unwrap();
        assert_eq!(e.collisions, 0, "{strategy:?}: {e:?}");
        // The wall between the rooms is x = 6 for y > 2; the only way across it is the
        // corridor to the south (y < 2).
        for w in states.windows(2) {
            let (p, q) = (w[0].position, w[1].position);
            let crossed = (p.x - 6.0).signum() != (q.x - 6.0).signum();
            assert!(
                !(crossed && p.y.min(q.y) > 2.0),
                "{strategy:?}: crossed the wall at ({:.2}, {:.2}), t = {:.1} s",
                q.x,
                q.y,
                w[1].t_s
            );
        }
    }
}

#[test]
fn a_room_without_a_way_out_is_explored_and_the_vehicle_lands_at_home() {
    let (report, _) = explore(
        World::parse(CLOSED_ROOM).unwrap(),
        4,
        240.0,
        Strategy::Frontier,
    );
    let e = report.score.explore.as_ref().unwrap();
    assert!(e.explored_fraction > 0.9, "{e:?}");
    assert!(e.explore_end.is_some(), "{e:?}");
    assert!(e.returned_home && e.landed, "{e:?}");
    assert_eq!(e.collisions, 0, "{e:?}");
}

#[test]
fn a_person_walking_across_the_room_causes_no_collision() {
    // The room's person walks back and forth across its middle, where the vehicle explores.
    let (report, _) = explore(shipped("room"), 8, 90.0, Strategy::Frontier);
    let e = report.score.explore.as_ref().unwrap();
    assert_eq!(e.collisions, 0, "{e:?}");
    assert!(e.min_clearance_m >= 0.35, "{e:?}");
}

#[test]
fn a_person_walking_at_the_vehicle_is_sidestepped_with_r_min_to_spare() {
    // In these flights the person walks along its line straight at the vehicle, which used to
    // flee along that line and be caught (seed 2 twice within 20 s, 0.29 m from the person).
    for seed in [2, 6] {
        let (report, _) = explore(shipped("room"), seed, 90.0, Strategy::Frontier);
        let e = report.score.explore.as_ref().unwrap();
        assert_eq!(e.collisions, 0, "seed {seed}: {e:?}");
        assert!(e.min_clearance_m >= 0.40, "seed {seed}: {e:?}");
        assert!(e.returned_home && e.landed, "seed {seed}: {e:?}");
    }
}

#[test]
fn a_featureless_corridor_is_reported_degenerate_and_never_flown_to_its_end() {
    // 40 m of smooth walls seen by a 4 m lidar: the SLAM cannot tell how far along it is. Its
    // pose fixes say so, the estimate is not pinned to its guess, and the vehicle lands when
    // it no longer knows where it is instead of running down the corridor into the far wall
    // (x = 46 m) at whatever speed the unobserved axis reached. That landing still knows the
    // position across the corridor and holds it: a level landing drifted half a metre toward
    // a wall. The drag reading bounds the speed along the corridor, so the estimate lasts
    // longer than a minute here: the flight is given two.
    let (report, states) = explore(
        World::parse(LONG_CORRIDOR).unwrap(),
        1,
        120.0,
        Strategy::Frontier,
    );
    let e = report.score.explore.as_ref().unwrap();
    let log = &report.exploration.as_ref().unwrap().companion;
    assert!(log.degenerate_s > 5.0, "{log:?}");
    assert_eq!(e.collisions, 0, "{e:?}");
    assert!(e.landed, "{e:?}");
    let farthest = states.iter().map(|s| s.position.x).fold(f64::MIN, f64::max);
    assert!(farthest < 15.0, "flew to x = {farthest} m");
    // The corridor's centre line is y = 1 m.
    let down = states.last().unwrap().position;
    assert!((down.y - 1.0).abs() < 0.25, "landed at y = {:.2} m", down.y);
}

#[test]
fn a_featureless_corridor_ends_exploring_while_the_way_back_still_fits() {
    // Past the start room's wall nothing along the corridor is within the XV-11's reach: the
    // estimate's one-sigma along it grows from the moment that wall drops out of range. The
    // companion ends exploring while flying back as far as it came still fits in the flight
    // part's bound, instead of exploring on until the flight part lands wherever the bound
    // runs out; the vehicle comes back toward the start room.
    for strategy in [Strategy::Frontier, Strategy::WallFollow] {
        let (report, states) = explore(World::parse(LONG_CORRIDOR).unwrap(), 3, 120.0, strategy);
        let e = report.score.explore.as_ref().unwrap();
        let log = &report.exploration.as_ref().unwrap().companion;
        assert!(
            matches!(log.explore_end, Some((_, ExploreEnd::BlindBudget))),
            "{strategy:?}: {:?}",
            log.explore_end
        );
        assert_eq!(e.collisions, 0, "{strategy:?}: {e:?}");
        assert!(e.landed, "{strategy:?}: {e:?}");
        let farthest = states.iter().map(|s| s.position.x).fold(f64::MIN, f64::max);
        let down = states.last().unwrap().position.x;
        assert!(
            down < farthest - 1.0,
            "{strategy:?}: landed at x = {down:.2} m, farthest {farthest:.2} m"
        );
    }
}

#[test]
fn a_way_home_through_a_gap_only_the_map_has_is_planned_round_and_flown_home() {
    // Office seed 3: exploring ends at 144.5 s with the live map missing 1.9 m of the corridor's
    // north wall (x 15.0 to 16.9), and the way home planned through it. The field cannot fly
    // through the real wall; after 30 s without progress the way is planned round the place
    // and the vehicle comes home through the door (it used to hover there until 600 s).
    let (report, _) = explore(shipped("office"), 3, 300.0, Strategy::Frontier);
    let e = report.score.explore.as_ref().unwrap();
    assert!(e.returned_home && e.landed, "{e:?}");
    assert_eq!(e.failsafe, None, "{e:?}");
}

#[test]
fn a_home_against_a_wall_is_not_landed_at() {
    // The closed room with the take-off point 0.45 m from its south wall: inside the 0.5 m
    // the guidance keeps from walls (the vehicle's radius is 0.35 m). A drifted map can put
    // home there too (building flights 3.5 m off along a corridor flew into the wall while
    // landing at a home 0.25 m from it). Coming back, the landing spot must keep clear of what
    // the scan sees, so the vehicle lands beside home, not at it.
    let world = CLOSED_ROOM.replace("start 1.5 2.5 0.0", "start 1.5 0.45 0.0");
    let (report, states) = explore(World::parse(&world).unwrap(), 1, 120.0, Strategy::Frontier);
    let e = report.score.explore.as_ref().unwrap();
    let companion = &report.exploration.as_ref().unwrap().companion;
    assert_eq!(e.collisions, 0, "{e:?}");
    assert!(e.landed, "{e:?}");
    assert!(companion.landed_off_home, "{e:?}");
    let down = states.last().unwrap().position;
    assert!(down.y >= 0.5, "landed {:.2} m from the south wall", down.y);
}
