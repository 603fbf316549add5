//! The exploration mission closed loop: the test vehicle, the autopilot and a scripted companion
//! whose map frame is turned and shifted against the world, sending pose fixes, setpoints,
//! mission commands and the path-home length at 5 Hz.

extern crate std;

use super::events::EventKind;
use super::mission::{transition, Energy, Mission, MissionConfig, MissionStatus};
use super::test_vehicle::TestVehicle;
use super::tests::{config, Flight};
use crate::estimate::pose_fix::CompanionFrame;
use crate::geom::{Pose2, Vec2};
use crate::msgs::{
    CompanionMessages, CompanionSetpoint, EstimatedState, FailsafeReason, FlightMode, Inputs,
    MissionCommand, Outputs, PoseFix, SetpointTarget,
};
use libm::hypotf;
use std::vec::Vec;

/// Steps between companion messages: 5 Hz at the tests' 500 Hz.
const EVERY: u64 = 100;

struct Companion {
    /// True world -> the companion's map.
    world_to_map: Pose2,
    reset_counter: u8,
    /// The world point (x, y) to fly to, or the world velocity (vx, vy) to fly.
    goal: Option<Goal>,
    /// Sent once, with the next message.
    command: Option<MissionCommand>,
    path_home_m: Option<f32>,
    step: u64,
}

#[derive(Clone, Copy)]
enum Goal {
    Point([f32; 2]),
    Velocity([f32; 2]),
}

impl Companion {
    fn new() -> Self {
        Self {
            world_to_map: Pose2::new(1.0, -2.0, 0.6),
            reset_counter: 3,
            goal: None,
            command: None,
            path_home_m: None,
            step: 0,
        }
    }

    /// What it sends this step, from the vehicle's true pose (its SLAM is perfect here).
    fn send(&mut self, inputs: &mut Inputs, v: &TestVehicle) {
        self.step += 1;
        if !self.step.is_multiple_of(EVERY) {
            return;
        }
        let (_, _, yaw) = v.roll_pitch_yaw();
        let map = self
            .world_to_map
            .compose(Pose2::new(v.position_m.x, v.position_m.y, yaw));
        let t_s = inputs.t_s;
        let target = self.goal.map(|g| match g {
            Goal::Point([x, y]) => {
                let p = self.world_to_map.transform(Vec2::new(x, y));
                SetpointTarget::Position {
                    position_m: [p.x, p.y],
                    yaw_rad: self.world_to_map.theta,
                }
            }
            Goal::Velocity([x, y]) => {
                let d = self.world_to_map.rotate(Vec2::new(x, y));
                SetpointTarget::Velocity {
                    velocity_m_s: [d.x, d.y],
                    yaw_rad: self.world_to_map.theta,
                }
            }
        });
        inputs.companion = CompanionMessages {
            pose: Some(PoseFix {
                t_s,
                position_m: [map.x, map.y],
                yaw_rad: map.theta,
                covariance: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
                quality_pct: Some(90),
                reset_counter: self.reset_counter,
            }),
            setpoint: target.map(|target| CompanionSetpoint { t_s, target }),
            command: self.command.take(),
            path_home_m: self.path_home_m,
        };
    }
}

/// Flies `secs` with the companion talking; `watch` sees every step.
fn fly(f: &mut Flight, c: &mut Companion, secs: f32, watch: impl FnMut(&Outputs, &TestVehicle)) {
    f.fly_with(secs, |i, v| c.send(i, v), watch);
}

fn modes(f: &Flight) -> Vec<FlightMode> {
    f.ap.events()
        .iter()
        .filter_map(|e| match e.kind {
            EventKind::ModeChange { to, .. } => Some(to),
            EventKind::Failsafe(_)
            | EventKind::AdaptiveFallback(_)
            | EventKind::EstimateDegraded(_) => None,
        })
        .collect()
}

/// Takes off with the companion talking and starts exploring.
fn explore(seed: u64, c: &mut Companion) -> Flight {
    let mut f = Flight::new(config(), seed);
    fly(&mut f, c, 0.2, |_, _| {});
    f.veh.pilot.arm = true;
    c.command = Some(MissionCommand::StartExplore);
    fly(&mut f, c, 6.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Explore, "{:?}", modes(&f));
    f
}

#[test]
fn the_mission_explores_returns_and_lands_at_the_take_off_point() {
    let mut c = Companion::new();
    c.path_home_m = Some(0.0);
    c.goal = Some(Goal::Velocity([0.4, 0.0]));
    let mut f = explore(11, &mut c);
    // Flying the velocity setpoint: world +x at about 0.4 m/s, at the hold height.
    let x0 = f.veh.position_m.x;
    fly(&mut f, &mut c, 3.0, |_, _| {});
    let speed = (f.veh.position_m.x - x0) / 3.0;
    assert!((0.3..0.5).contains(&speed), "speed {speed}");
    assert!(f.veh.position_m.y.abs() < 0.1 && (f.veh.position_m.z - 1.0).abs() < 0.1);
    // Then a position setpoint off to the side.
    c.goal = Some(Goal::Point([1.5, 1.0]));
    fly(&mut f, &mut c, 5.0, |_, _| {});
    let (dx, dy) = (f.veh.position_m.x - 1.5, f.veh.position_m.y - 1.0);
    assert!(hypotf(dx, dy) < 0.1, "{dx} {dy}");
    // Done: the companion leads home over a waypoint, and the vehicle lands there.
    c.command = Some(MissionCommand::ExploreDone);
    c.goal = Some(Goal::Point([0.0, 1.0]));
    c.path_home_m = Some(2.5);
    fly(&mut f, &mut c, 4.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Return);
    c.goal = Some(Goal::Point([0.0, 0.0]));
    fly(&mut f, &mut c, 10.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Disarmed, "{:?}", modes(&f));
    use FlightMode::*;
    assert_eq!(modes(&f), [Takeoff, Hold, Explore, Return, Land, Disarmed]);
    assert!(f.horizontal_error_m() < 0.1, "{}", f.horizontal_error_m());
    assert_eq!(f.out.failsafe, None);
    let fixes = f.ap.companion_frame().counters();
    assert!(fixes.accepted > 100 && fixes.anchors == 1, "{fixes:?}");
}

#[test]
fn stale_setpoints_hold_and_a_silent_companion_lands_in_place() {
    let mut c = Companion::new();
    c.goal = Some(Goal::Velocity([0.4, 0.0]));
    let mut f = explore(12, &mut c);
    fly(&mut f, &mut c, 2.0, |_, _| {});
    // The companion stops sending setpoints (its pose fixes keep coming).
    c.goal = None;
    fly(&mut f, &mut c, 1.5, |_, _| {});
    let stopped = f.veh.position_m;
    let mut worst = 0.0f32;
    fly(&mut f, &mut c, 3.0, |o, v| {
        assert_eq!(o.mode, FlightMode::Explore);
        worst = worst.max(hypotf(
            v.position_m.x - stopped.x,
            v.position_m.y - stopped.y,
        ));
    });
    assert!(worst < 0.1, "drifted {worst} m while holding");
    assert!(f.ap.mission().counters().stale_steps > 1000);
    // Five seconds without a setpoint: land where it is.
    fly(&mut f, &mut c, 1.0, |_, _| {});
    assert_eq!(
        (f.out.mode, f.out.failsafe),
        (FlightMode::Land, Some(FailsafeReason::CompanionLost))
    );
    fly(&mut f, &mut c, 6.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    let d = hypotf(
        f.veh.position_m.x - stopped.x,
        f.veh.position_m.y - stopped.y,
    );
    assert!(d < 0.15, "landed {d} m from where it stopped");
}

/// Explores at 0.3 m/s until the pack sags below the low threshold with the companion giving
/// `path_home_m`; returns the mode and failsafe after the battery decision.
fn low_battery_with_path_home(path_home_m: f32) -> Flight {
    let mut c = Companion::new();
    c.path_home_m = Some(path_home_m);
    c.goal = Some(Goal::Velocity([0.3, 0.0]));
    let mut f = explore(13, &mut c);
    fly(&mut f, &mut c, 2.0, |_, _| {});
    f.veh.battery_v = 10.3;
    c.goal = Some(Goal::Point([0.0, 0.0]));
    fly(&mut f, &mut c, 2.0, |_, _| {});
    f
}

#[test]
fn low_battery_returns_when_the_way_home_is_covered_and_lands_in_place_when_not() {
    // 10.3 V leaves about 3.3 Wh above the critical voltage: a 1 m way home needs 0.2 Wh.
    let mut near = low_battery_with_path_home(1.0);
    assert_eq!(
        (near.out.mode, near.out.failsafe),
        (FlightMode::Return, Some(FailsafeReason::BatteryLow))
    );
    let mut c = Companion::new();
    c.goal = Some(Goal::Point([0.0, 0.0]));
    c.path_home_m = Some(0.5);
    fly(&mut near, &mut c, 10.0, |_, _| {});
    assert_eq!(near.out.mode, FlightMode::Disarmed);
    assert!(
        near.horizontal_error_m() < 0.1,
        "{}",
        near.horizontal_error_m()
    );
    // 60 m home at 0.5 m/s needs about 5.7 Wh with the margin: land here, not at home.
    let far = low_battery_with_path_home(60.0);
    assert_eq!(
        (far.out.mode, far.out.failsafe),
        (FlightMode::Land, Some(FailsafeReason::BatteryLow))
    );
    assert!(
        far.horizontal_error_m() > 0.4,
        "{}",
        far.horizontal_error_m()
    );
}

#[test]
fn the_energy_budget_turns_back_before_the_margin_is_used() {
    let mut m = Mission::new(MissionConfig::default());
    let away = |m: &Mission| m.status(0.0, [5.0, 0.0], [0.0; 2], 2.0);
    let send = |m: &mut Mission, path: f32, v: f32| {
        let msgs = CompanionMessages {
            path_home_m: Some(path),
            ..CompanionMessages::default()
        };
        // A long step settles the smoothed voltage at once.
        m.observe(0.0, &msgs, Some(v), 10.0);
    };
    assert_eq!(away(&m).energy, Energy::Unknown);
    // Full pack, 20 m home: plenty.
    send(&mut m, 20.0, 12.6);
    assert_eq!(away(&m).energy, Energy::Plenty);
    // 11.0 V is about 9 Wh: 20 m needs 2.0 Wh with the margin, 20 s of look-ahead 0.7 Wh.
    send(&mut m, 20.0, 11.0);
    assert_eq!(away(&m).energy, Energy::Plenty);
    // 90 m needs 8.5 Wh: covered, but not for 20 s more; 100 m needs 9.5 Wh: short.
    send(&mut m, 90.0, 11.0);
    let turn_back = away(&m);
    assert_eq!(turn_back.energy, Energy::TurnBack);
    assert_eq!(
        transition(FlightMode::Explore, &turn_back, false),
        Some((FlightMode::Return, None))
    );
    send(&mut m, 100.0, 11.0);
    let short = away(&m);
    assert_eq!(short.energy, Energy::Short);
    assert_eq!(
        transition(FlightMode::Explore, &short, false),
        Some((FlightMode::Land, Some(FailsafeReason::BatteryLow)))
    );
    // A return in progress keeps going unless the low-voltage failsafe says it cannot.
    assert_eq!(transition(FlightMode::Return, &short, false), None);
    assert_eq!(
        transition(FlightMode::Return, &short, true),
        Some((FlightMode::Land, Some(FailsafeReason::BatteryLow)))
    );
    // A bad path length is refused and counted; the last good one stays.
    let bad = CompanionMessages {
        path_home_m: Some(f32::NAN),
        ..CompanionMessages::default()
    };
    m.observe(0.0, &bad, None, 0.002);
    assert_eq!(m.counters().bad_path_home, 1);
    assert_eq!(away(&m).energy, Energy::Short);
    // Without a mission nothing moves the hold.
    assert_eq!(
        transition(FlightMode::Hold, &MissionStatus::default(), true),
        None
    );
}

#[test]
fn a_re_localisation_re_anchors_and_the_vehicle_keeps_its_place() {
    let mut c = Companion::new();
    c.goal = Some(Goal::Point([1.0, 0.5]));
    let mut f = explore(14, &mut c);
    fly(&mut f, &mut c, 5.0, |_, _| {});
    let est = |f: &Flight| f.out.estimate.position_m;
    let largest_step = |f: &mut Flight, c: &mut Companion| {
        let (mut largest, mut last) = (0.0f32, est(f));
        fly(f, c, 5.0, |o, _| {
            let p = o.estimate.position_m;
            largest = largest.max(hypotf(p[0] - last[0], p[1] - last[1]));
            last = p;
        });
        largest
    };
    let steady = largest_step(&mut f, &mut c);
    // The companion's map jumps by 0.6 m and a turn (a loop closure) and it says so; its
    // setpoint now names the same place in the jumped map.
    c.world_to_map = Pose2::new(1.5, -1.7, 0.7);
    c.reset_counter = c.reset_counter.wrapping_add(1);
    let after = largest_step(&mut f, &mut c);
    // No step larger than the revolutions' own corrections, far below the 0.6 m of the jump.
    std::println!("largest estimate step: steady {steady} m, after the jump {after} m");
    assert!(
        after < 2.0 * steady + 0.005,
        "the estimate jumped {after} m"
    );
    assert_eq!(f.ap.companion_frame().counters().anchors, 2);
    let (dx, dy) = (f.veh.position_m.x - 1.0, f.veh.position_m.y - 0.5);
    assert!(hypotf(dx, dy) < 0.1, "{dx} {dy}");
    assert_eq!(f.out.mode, FlightMode::Explore);
}

#[test]
fn bad_pose_fixes_are_refused_and_counted_in_flight() {
    let mut c = Companion::new();
    c.goal = Some(Goal::Point([0.5, 0.0]));
    let mut f = explore(15, &mut c);
    let accepted = f.ap.companion_frame().counters().accepted;
    let mut k = 0;
    f.fly_with(
        2.0,
        |i, v| {
            c.send(i, v);
            if let Some(p) = &mut i.companion.pose {
                k += 1;
                // Not a number, and wider than the bounds in every direction of position (wide
                // in one direction only is a corridor's fix, fused across it).
                match k % 2 {
                    0 => p.covariance[0][0] = f32::NAN,
                    _ => {
                        p.covariance[0][0] = 1e9;
                        p.covariance[1][1] = 1e9;
                    }
                }
            }
        },
        |o, _| assert!(o.estimate.position_m.iter().all(|v| v.is_finite())),
    );
    let fixes = f.ap.companion_frame().counters();
    assert_eq!((fixes.invalid, fixes.accepted), (10, accepted), "{fixes:?}");
    assert_eq!(f.out.mode, FlightMode::Explore);
}

#[test]
fn the_time_budget_ends_exploring() {
    let mut c = Companion::new();
    c.goal = Some(Goal::Point([0.3, 0.0]));
    let mut cfg = config();
    cfg.mission.explore_budget_s = 3.0;
    let mut f = Flight::new(cfg, 16);
    fly(&mut f, &mut c, 0.2, |_, _| {});
    f.veh.pilot.arm = true;
    c.command = Some(MissionCommand::StartExplore);
    fly(&mut f, &mut c, 10.0, |_, _| {});
    assert_eq!((f.out.mode, f.out.failsafe), (FlightMode::Return, None));
    let entered = |mode| {
        f.ap.events()
            .iter()
            .find(|e| matches!(e.kind, EventKind::ModeChange { to, .. } if to == mode))
            .map(|e| e.t_s)
            .unwrap()
    };
    let explored_s = entered(FlightMode::Return) - entered(FlightMode::Explore);
    assert!((explored_s - 3.0).abs() < 0.01, "{explored_s}");
}

#[test]
fn failsafes_kill_switch_and_takeover_act_during_a_mission_as_in_hold() {
    // Lidar lost: hold on the IMU (not chasing the setpoints), then land where it is.
    let mut c = Companion::new();
    c.goal = Some(Goal::Velocity([0.3, 0.0]));
    let mut f = explore(17, &mut c);
    fly(&mut f, &mut c, 1.0, |_, _| {});
    f.veh.lidar_on = false;
    fly(&mut f, &mut c, 1.5, |_, _| {});
    assert_eq!(
        (f.out.mode, f.out.failsafe),
        (FlightMode::Explore, Some(FailsafeReason::LidarLost))
    );
    let held = f.veh.position_m;
    fly(&mut f, &mut c, 0.4, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Explore);
    let moved = hypotf(f.veh.position_m.x - held.x, f.veh.position_m.y - held.y);
    assert!(
        moved < 0.15,
        "kept flying the setpoints on the IMU: {moved} m"
    );
    fly(&mut f, &mut c, 0.5, |_, _| {});
    assert_eq!(
        (f.out.mode, f.out.failsafe),
        (FlightMode::Land, Some(FailsafeReason::LidarLost))
    );

    // Manual takeover and hand-back: the pilot gets a hold, not the mission again.
    let mut c = Companion::new();
    c.goal = Some(Goal::Velocity([0.3, 0.0]));
    let mut f = explore(18, &mut c);
    f.veh.pilot.manual = true;
    f.veh.pilot.throttle_norm = 0.35;
    fly(&mut f, &mut c, 0.5, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Manual);
    f.veh.pilot.manual = false;
    fly(&mut f, &mut c, 1.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Hold);

    // Kill switch: motors stop on the step it is seen.
    let mut c = Companion::new();
    c.goal = Some(Goal::Velocity([0.3, 0.0]));
    let mut f = explore(19, &mut c);
    f.veh.pilot.kill = true;
    fly(&mut f, &mut c, 0.002, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Killed);
    assert_eq!(f.out.motors.throttle_norm, [0.0; 4]);
}

#[test]
fn a_lost_ground_link_stops_a_mission_where_it_is() {
    let mut c = Companion::new();
    let mut f = explore(31, &mut c);
    c.goal = Some(Goal::Point([1.5, 1.0]));
    let linked = |f: &mut Flight, c: &mut Companion, secs, hb| {
        f.fly_with(
            secs,
            |i, v| (c.send(i, v), i.ground.heartbeat = hb).1,
            |_, _| {},
        )
    };
    linked(&mut f, &mut c, 6.0, true);
    assert_eq!(f.out.mode, FlightMode::Explore);
    // Heartbeats stop: it holds where it is, neither at the take-off point nor where the
    // companion now asks to go.
    linked(&mut f, &mut c, 3.1, false);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::LinkLost));
    let stopped = [f.veh.position_m.x, f.veh.position_m.y];
    assert!(hypotf(stopped[0], stopped[1]) > 1.5, "{stopped:?}");
    c.goal = Some(Goal::Point([0.0, 0.0]));
    linked(&mut f, &mut c, 5.0, false);
    let moved = hypotf(
        f.veh.position_m.x - stopped[0],
        f.veh.position_m.y - stopped[1],
    );
    assert!(moved < 0.3, "drifted {moved} m towards the start");
}

#[test]
fn setpoints_age_by_the_autopilot_clock() {
    let mut m = Mission::new(MissionConfig::default());
    let (frame, e) = (CompanionFrame::default(), EstimatedState::default());
    let at = |t_s| CompanionMessages {
        setpoint: Some(CompanionSetpoint {
            t_s,
            target: SetpointTarget::Position {
                position_m: [1.0, 2.0],
                yaw_rad: 0.5,
            },
        }),
        ..CompanionMessages::default()
    };
    // Stamped an hour ahead (a companion clock gone wrong): refused, and the vehicle holds.
    m.observe(10.0, &at(3610.0), None, 0.002);
    assert_eq!(m.counters().bad_setpoints, 1);
    assert_eq!(m.target(10.0, &frame, &e, 1.5, false), [0.0; 3]);
    // A little ahead: flown, and stale a timeout after it arrived, not after its stamp.
    m.observe(20.0, &at(20.3), None, 0.002);
    assert_eq!(m.target(20.5, &frame, &e, 1.5, false), [1.0, 2.0, 0.5]);
    assert_eq!(m.target(20.7, &frame, &e, 1.5, false), [0.0; 3]);
}

#[test]
fn a_companion_that_gives_up_the_way_home_lands_in_place_with_the_reason() {
    let mut c = Companion::new();
    c.path_home_m = Some(5.0);
    c.goal = Some(Goal::Velocity([0.4, 0.0]));
    let mut f = explore(13, &mut c);
    // Away from home, then stuck: the companion's setpoint goes nowhere.
    fly(&mut f, &mut c, 4.0, |_, _| {});
    c.goal = Some(Goal::Velocity([0.0, 0.0]));
    c.command = Some(MissionCommand::ExploreDone);
    fly(&mut f, &mut c, 1.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Return, "{:?}", modes(&f));
    let stopped = f.veh.position_m;
    c.command = Some(MissionCommand::LandHere);
    fly(&mut f, &mut c, 0.3, |_, _| {});
    assert_eq!(
        (f.out.mode, f.out.failsafe),
        (FlightMode::Land, Some(FailsafeReason::NoProgress))
    );
    fly(&mut f, &mut c, 8.0, |_, _| {});
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    let d = hypotf(
        f.veh.position_m.x - stopped.x,
        f.veh.position_m.y - stopped.y,
    );
    assert!(d < 0.15, "landed {d} m from where it gave up");
}

/// A revolution of a wall across world x at `wall_x` (m), seen from the vehicle's true pose,
/// as the lidar would hand it over: up to 6 m, a beam a degree.
fn wall_ahead(v: &TestVehicle, wall_x: f32) -> crate::guidance::nearest_hits::NearestHits {
    use crate::scan::{Beam, Scan};
    let (_, _, yaw) = v.roll_pitch_yaw();
    let mut scan: Scan<360> = Scan::new(v.t_s);
    for i in 0..360 {
        let bearing = (i as f32).to_radians();
        let c = libm::cosf(yaw + bearing);
        let range = (wall_x - v.position_m.x) / c;
        let beam = if c > 1e-3 && range < 6.0 {
            Beam::new(bearing, range)
        } else {
            Beam::invalid(bearing)
        };
        scan.push(beam).unwrap();
    }
    crate::guidance::nearest_hits::NearestHits::of_scan(&scan)
}

#[test]
fn a_setpoint_into_a_wall_the_flight_part_sees_is_not_flown() {
    // The companion's commands come from its own frame; when that frame has gone wrong (a SLAM
    // heading that slid while the autopilot refused its fixes) a velocity it guarded along a
    // wall points, in the autopilot's frame, straight at it. The flight part sees the wall in
    // its own scans and must keep r_min from it whatever it is asked.
    let mut c = Companion::new();
    let mut f = explore(21, &mut c);
    let wall_x = f.veh.position_m.x + 1.2;
    c.goal = Some(Goal::Velocity([0.5, 0.0]));
    let r_min = MissionConfig::default().guard.r_min_m;
    let mut closest = f32::INFINITY;
    for _ in 0..40 {
        let hits = wall_ahead(&f.veh, wall_x);
        f.ap.observe_hits(hits);
        fly(&mut f, &mut c, 0.2, |_, v| {
            closest = closest.min(wall_x - v.position_m.x);
        });
    }
    assert_eq!(f.out.mode, FlightMode::Explore);
    // Not even the velocity loop's lag carries it inside r_min (a millimetre for rounding).
    assert!(
        closest > r_min - 0.001,
        "{closest} m from the wall, r_min {r_min} m"
    );
    assert!(f.ap.mission().counters().guarded_steps > 0);
    // It went as near as the guard lets it, not stopped short.
    assert!(closest < r_min + 0.1, "{closest} m from the wall");
}
