//! Seed 002's guidance on known scenes: a room, a corridor, a door wider and narrower than the
//! gap threshold, a dead end, and scans with nothing usable in them.

#[allow(dead_code)] // each test binary uses its own share of the shared scenes
mod synthetic;

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::guidance::guard::respects_every_hit;
use plumbline_core::guidance::{
    Guard, Guidance, GuidanceCommand, GuidanceConfig, GuidanceMode, HeadingRule, Outcome,
};
use plumbline_core::scan::{Beam, Scan};
use std::f32::consts::{PI, TAU};
use synthetic::{scan_within, Seg};

const BEAMS: usize = 360;
/// The simulated XV-11's reach.
const RANGE_M: f32 = 6.0;

fn wall(a: (f32, f32), b: (f32, f32)) -> Seg {
    (Vec2::new(a.0, a.1), Vec2::new(b.0, b.1))
}

fn rect(x0: f32, y0: f32, x1: f32, y1: f32) -> Vec<Seg> {
    vec![
        wall((x0, y0), (x1, y0)),
        wall((x1, y0), (x1, y1)),
        wall((x1, y1), (x0, y1)),
        wall((x0, y1), (x0, y0)),
    ]
}

fn look(world: &[Seg], pose: Pose2) -> Scan<BEAMS> {
    scan_within(world, pose, BEAMS, TAU, 0.0, 1, RANGE_M)
}

fn step(world: &[Seg], pose: Pose2, mode: GuidanceMode) -> (GuidanceCommand, Guidance<64>) {
    let mut g = Guidance::<64>::new(GuidanceConfig::default()).unwrap();
    let cmd = g.step(&look(world, pose), pose, mode);
    (cmd, g)
}

fn wall_follow(world: &[Seg], pose: Pose2) -> GuidanceCommand {
    step(world, pose, GuidanceMode::WallFollow).0
}

fn speed(c: &GuidanceCommand) -> f32 {
    Vec2::new(c.velocity_world_m_s[0], c.velocity_world_m_s[1]).norm()
}

fn angle_close(a: f32, b: f32, tol: f32) -> bool {
    plumbline_core::geom::normalize_angle(a - b).abs() < tol
}

/// A straight corridor along x, `width_m` wide, 100 m long.
fn corridor(width_m: f32) -> Vec<Seg> {
    let h = width_m / 2.0;
    vec![wall((-50.0, -h), (50.0, -h)), wall((-50.0, h), (50.0, h))]
}

#[test]
fn room_walls_are_found_and_the_right_wall_is_followed_forward() {
    let room = rect(-3.0, -2.0, 3.0, 2.0);
    let pose = Pose2::new(0.0, -0.8, 0.0); // right wall at r_goal = 1.2 m
    let (cmd, g) = step(&room, pose, GuidanceMode::WallFollow);
    let walls = g.walls();
    println!("{:#?}\n{:#?}", walls.segments(), walls.gaps());
    // Four walls; the one on the right is cut where the rules' sweep begins, so five pieces.
    assert_eq!(walls.segments().len(), 5, "{:?}", walls.segments());
    for s in walls.segments() {
        let on_a_wall = [(-PI / 2.0, 1.2), (0.0, 3.0), (PI / 2.0, 2.8), (PI, 3.0)]
            .iter()
            .any(|&(a, r)| angle_close(s.normal_rad, a, 1e-3) && (s.distance_m - r).abs() < 1e-3);
        assert!(on_a_wall && s.rms_residual_m < 1e-3, "{s:?}");
    }
    // Corners are the only openings: no gap to fly through.
    assert!(
        walls.gaps().iter().all(|g| g.width_m < 0.2),
        "{:?}",
        walls.gaps()
    );
    // No exit on the way round: the farthest wall in the sweep (the far side) points back.
    assert!(matches!(
        cmd.decision.outcome,
        Outcome::WallFollow(HeadingRule::DeadEnd { .. })
    ));
    let [vx, vy] = cmd.velocity_world_m_s;
    println!("room: v = ({vx:.3}, {vy:.3}) m/s, {:?}", cmd.decision);
    assert!(
        vx > 0.1 && vx > 2.0 * vy.abs(),
        "along the right wall, forward: {vx} {vy}"
    );
    assert!((cmd.nearest_range_m.unwrap() - 1.2).abs() < 1e-3);
    assert!(!cmd.decision.centred);
}

#[test]
fn a_narrow_corridor_is_flown_centred_and_forward() {
    let world = corridor(2.0);
    for y in [-0.4f32, -0.15, 0.0, 0.15, 0.4] {
        let cmd = wall_follow(&world, Pose2::new(0.0, y, 0.0));
        let [vx, vy] = cmd.velocity_world_m_s;
        println!(
            "corridor y {y:+.2}: v = ({vx:.3}, {vy:.3}) {:?}",
            cmd.decision
        );
        assert!(cmd.decision.centred);
        assert!((cmd.decision.free_width_m.unwrap() - 2.0).abs() < 1e-3);
        // Cruise speed, less what centring needs under the 0.5 m/s limit.
        let along = (0.25 - y * y).sqrt().min(0.4);
        assert!((vx - along).abs() < 1e-3, "along the corridor: {vx}");
        // Toward the middle, in proportion to the offset (centring gain 1 /s).
        assert!((vy + y).abs() < 1e-3, "y {y}: vy {vy}");
        assert!(matches!(
            cmd.decision.outcome,
            Outcome::WallFollow(HeadingRule::FollowWall { gap: Some(_), .. })
        ));
        assert!(angle_close(cmd.yaw_rad.unwrap(), 0.0, 1e-3));
    }
}

#[test]
fn a_featureless_corridor_never_pushes_toward_a_wall() {
    // Every offset and heading across the corridor: the velocity never closes on the nearer
    // wall faster than the guard allows, and always heads back to the middle.
    let world = corridor(2.0);
    let cfg = GuidanceConfig::default();
    for i in 0..=12 {
        let y = -0.45 + 0.9 * i as f32 / 12.0;
        for yaw in [-0.6f32, -0.3, 0.0, 0.3, 0.6] {
            let pose = Pose2::new(0.0, y, yaw);
            let scan = look(&world, pose);
            let mut g = Guidance::<64>::new(cfg).unwrap();
            let cmd = g.step(&scan, pose, GuidanceMode::WallFollow);
            let v = pose.inverse().rotate(Vec2::new(
                cmd.velocity_world_m_s[0],
                cmd.velocity_world_m_s[1],
            ));
            assert!(respects_every_hit(v, &scan, &cfg), "y {y} yaw {yaw}");
            let vy = cmd.velocity_world_m_s[1];
            if y.abs() > 0.05 {
                assert!(
                    vy * y < 0.0,
                    "y {y} yaw {yaw}: vy {vy} moves away from the middle"
                );
            }
        }
    }
}

/// A wall on the right (y = -1.2) with an opening from x = 1 to x = 1 + `door_m`, a room behind
/// it, and a far wall on the left.
fn wall_with_door(door_m: Option<f32>) -> Vec<Seg> {
    let mut w = vec![wall((30.0, 4.0), (-30.0, 4.0))];
    match door_m {
        Some(d) => {
            w.push(wall((-30.0, -1.2), (1.0, -1.2)));
            w.push(wall((1.0 + d, -1.2), (30.0, -1.2)));
            // The room behind the door: its side walls and back wall.
            w.push(wall((-2.0, -1.2), (-2.0, -5.0)));
            w.push(wall((-2.0, -5.0), (6.0, -5.0)));
            w.push(wall((6.0, -5.0), (6.0, -1.2)));
        }
        None => w.push(wall((-30.0, -1.2), (30.0, -1.2))),
    }
    w
}

#[test]
fn a_door_wider_than_the_threshold_is_taken() {
    let pose = Pose2::new(0.6, 0.0, 0.0);
    let (cmd, g) = step(&wall_with_door(Some(1.2)), pose, GuidanceMode::WallFollow);
    let closed = wall_follow(&wall_with_door(None), pose);
    let Outcome::WallFollow(HeadingRule::FollowWall {
        segment,
        gap: Some(gap),
    }) = cmd.decision.outcome
    else {
        panic!("{:?}", cmd.decision);
    };
    let gap = g.walls().gaps()[gap];
    println!(
        "door 1.2 m: gap {gap:?}, v {:?}, closed v {:?}",
        cmd.velocity_world_m_s, closed.velocity_world_m_s
    );
    // Hits are 3-8 cm apart on this wall: the width is the door's plus at most that.
    assert!(gap.width_m >= 1.2 && gap.width_m < 1.3, "{gap:?}");
    // The wall followed is the piece before the door, along x.
    let s = g.walls().segments()[segment];
    assert!(angle_close(s.direction_rad(), 0.0, 1e-3) && s.end_m.x < 1.0 - 0.6 + 0.01);
    // The opening bends the command toward it (toward -y), compared with an unbroken wall.
    assert!(
        cmd.velocity_world_m_s[1] < closed.velocity_world_m_s[1] - 0.02,
        "{:?} vs {:?}",
        cmd.velocity_world_m_s,
        closed.velocity_world_m_s
    );
}

#[test]
fn a_door_narrower_than_the_vehicle_is_flown_past() {
    let pose = Pose2::new(0.2, 0.0, 0.0);
    let (cmd, g) = step(&wall_with_door(Some(0.6)), pose, GuidanceMode::WallFollow);
    println!(
        "door 0.6 m: gaps {:?}, v {:?}",
        g.walls().gaps(),
        cmd.velocity_world_m_s
    );
    assert!(g
        .walls()
        .gaps()
        .iter()
        .any(|g| g.width_m >= 0.6 && g.width_m < 0.7));
    assert!(cmd.decision.narrow_gaps_flown_past >= 1);
    // The rules do not stop at it; and the command is the unbroken wall's, to a few mm/s.
    if let Outcome::WallFollow(HeadingRule::FollowWall { gap: Some(k), .. }) = cmd.decision.outcome
    {
        assert!(g.walls().gaps()[k].width_m >= 1.0);
    }
    // Wherever the door is, ahead, abeam or behind across the start of the sweep (x 1.8 and
    // 2.2 put it there), the command is the unbroken wall's, to a centimetre per second.
    for x in [0.2f32, 0.6, 1.0, 1.4, 1.8, 2.2, 2.6] {
        let pose = Pose2::new(x, 0.0, 0.0);
        let door = wall_follow(&wall_with_door(Some(0.6)), pose).velocity_world_m_s;
        let closed = wall_follow(&wall_with_door(None), pose).velocity_world_m_s;
        let dv = Vec2::new(door[0] - closed[0], door[1] - closed[1]);
        assert!(dv.norm() < 0.01, "x {x}: {door:?} vs {closed:?}");
    }
}

/// The second revolution's command at `pose`: a turn-around is taken when the rules choose
/// it on two revolutions running (the first holds the heading).
fn turned_around(world: &[Seg], pose: Pose2) -> GuidanceCommand {
    let mut g = Guidance::<64>::new(GuidanceConfig::default()).unwrap();
    let mut scan = look(world, pose);
    let first = g.step(&scan, pose, GuidanceMode::WallFollow);
    assert_eq!(first.yaw_rad, None, "{first:?}");
    scan.stamp_s += 0.2;
    g.step(&scan, pose, GuidanceMode::WallFollow)
}

#[test]
fn a_dead_end_turns_the_vehicle_around() {
    // A 3 m wide hallway (wider than 2 r_goal) closed 1.5 m ahead.
    let world = vec![
        wall((-30.0, -1.5), (1.5, -1.5)),
        wall((1.5, -1.5), (1.5, 1.5)),
        wall((1.5, 1.5), (-30.0, 1.5)),
    ];
    let cmd = turned_around(&world, Pose2::new(0.0, -0.3, 0.0));
    println!("dead end: {:?}", cmd);
    assert!(matches!(
        cmd.decision.outcome,
        Outcome::WallFollow(HeadingRule::DeadEnd { .. })
    ));
    assert!(
        angle_close(cmd.yaw_rad.unwrap(), PI, 1e-3),
        "{:?}",
        cmd.yaw_rad
    );
    // The field rounds the end as an inside corner (seed 002, Fig. 4): it turns left, and it
    // closes on the end wall no faster than the guard allows.
    let [vx, vy] = cmd.velocity_world_m_s;
    assert!(vy > 0.1, "{vy}");
    assert!(vx <= 1.0 * (1.5 - 0.5) + 1e-3);
    // Narrower than 2 r_goal: centred, and back out along the hallway.
    let narrow = vec![
        wall((-30.0, -0.9), (1.5, -0.9)),
        wall((1.5, -0.9), (1.5, 0.9)),
        wall((1.5, 0.9), (-30.0, 0.9)),
    ];
    let cmd = turned_around(&narrow, Pose2::new(0.0, 0.0, 0.0));
    assert!(cmd.decision.centred);
    assert!(matches!(
        cmd.decision.outcome,
        Outcome::WallFollow(HeadingRule::DeadEnd { .. })
    ));
    assert!(
        cmd.velocity_world_m_s[0] < -0.3,
        "{:?}",
        cmd.velocity_world_m_s
    );
}

/// The end of a 2 m corridor along x, closed at x = 0, with a 1.2 m door into a room on each
/// side just before the end (the shipped office's far end).
fn corridor_end_between_doors() -> Vec<Seg> {
    vec![
        wall((-20.0, -1.0), (-3.1, -1.0)),
        wall((-1.9, -1.0), (0.0, -1.0)),
        wall((-20.0, 1.0), (-3.1, 1.0)),
        wall((-1.9, 1.0), (0.0, 1.0)),
        wall((0.0, -5.0), (0.0, 5.0)),
        wall((-5.0, -5.0), (0.0, -5.0)),
        wall((-5.0, 5.0), (0.0, 5.0)),
        wall((-5.0, -5.0), (-5.0, -1.0)),
        wall((-5.0, 1.0), (-5.0, 5.0)),
    ]
}

#[test]
fn a_vehicle_that_does_not_turn_turns_around_at_a_dead_end_once() {
    // Flown kinematically, one command a revolution, by a vehicle whose body keeps its yaw (a
    // lidar that sees all round needs no turning): the rules must turn their own heading. Were
    // they to keep judging from body x, the end would read as a dead end and the way back as a
    // corridor with a door on the right at alternate revolutions, and the command would flip
    // between up and down the corridor.
    let world = corridor_end_between_doors();
    let cfg = GuidanceConfig::default();
    let dt = 0.2;
    for yaw in [0.0f32, -0.6, 0.6] {
        let mut g = Guidance::<64>::new(cfg).unwrap();
        let mut pose = Pose2::new(-8.0, 0.0, yaw);
        let (mut reversals, mut last_sign, mut deepest) = (0, 0.0f32, f32::NEG_INFINITY);
        for k in 0..200 {
            // The simulator's XV-11 reaches 4 m.
            let mut scan: Scan<BEAMS> = scan_within(&world, pose, BEAMS, TAU, 0.0, 1, 4.0);
            scan.stamp_s = k as f64 * dt as f64;
            let cmd = g.step(&scan, pose, GuidanceMode::WallFollow);
            let [vx, vy] = cmd.velocity_world_m_s;
            if vx.abs() > 0.2 {
                reversals += usize::from(last_sign != 0.0 && vx.signum() != last_sign);
                last_sign = vx.signum();
            }
            pose = Pose2::new(pose.x + vx * dt, pose.y + vy * dt, yaw);
            deepest = deepest.max(pose.x);
        }
        println!("yaw {yaw}: deepest x {deepest:.2}, end {pose:?}, reversals {reversals}");
        // Where the turn comes depends on where the rules' window starts (body x): within
        // reach of the doors at the end.
        assert!(
            deepest > -3.5,
            "yaw {yaw}: turned before the doors at the end ({deepest})"
        );
        assert_eq!(reversals, 1, "yaw {yaw}");
        assert!(
            pose.x < deepest - 4.0,
            "yaw {yaw}: not on the way back: {pose:?}"
        );
    }
}

#[test]
fn scans_with_nothing_usable_give_a_hover() {
    let mut all_invalid: Scan<BEAMS> = Scan::new(0.0);
    for i in 0..BEAMS {
        let a = -PI + TAU * i as f32 / BEAMS as f32;
        let beam = match i % 3 {
            0 => Beam::invalid(a),
            1 => Beam::new(a, f32::NAN),
            _ => Beam {
                valid: true,
                ..Beam::new(a, f32::INFINITY)
            },
        };
        all_invalid.push(beam).unwrap();
    }
    let empty: Scan<BEAMS> = Scan::new(0.0);
    for scan in [all_invalid, empty] {
        for mode in [
            GuidanceMode::WallFollow,
            GuidanceMode::TowardWaypoint {
                world_m: [3.0, 0.0],
            },
        ] {
            let mut g = Guidance::<64>::new(GuidanceConfig::default()).unwrap();
            let cmd = g.step(&scan, Pose2::new(1.0, 2.0, 0.3), mode);
            assert_eq!(cmd.velocity_world_m_s, [0.0, 0.0]);
            assert_eq!(cmd.yaw_rad, None);
            assert_eq!(cmd.nearest_range_m, None);
            assert_eq!(cmd.decision.outcome, Outcome::NoUsableBeams);
            assert!(g.walls().segments().is_empty() && g.walls().gaps().is_empty());
        }
    }
}

#[test]
fn a_bad_pose_or_waypoint_gives_a_hover_not_garbage() {
    let room = rect(-3.0, -2.0, 3.0, 2.0);
    let scan = look(&room, Pose2::new(0.0, 0.0, 0.0));
    let mut g = Guidance::<64>::new(GuidanceConfig::default()).unwrap();
    let cmd = g.step(
        &scan,
        Pose2::new(f32::NAN, 0.0, 0.0),
        GuidanceMode::WallFollow,
    );
    assert_eq!(
        (cmd.decision.outcome, cmd.velocity_world_m_s),
        (Outcome::InvalidEstimate, [0.0, 0.0])
    );
    let wp = GuidanceMode::TowardWaypoint {
        world_m: [f32::INFINITY, 0.0],
    };
    let cmd = g.step(&scan, Pose2::new(0.0, 0.0, 0.0), wp);
    assert_eq!(
        (cmd.decision.outcome, cmd.velocity_world_m_s),
        (Outcome::InvalidWaypoint, [0.0, 0.0])
    );
}

#[test]
fn toward_a_waypoint_the_field_still_keeps_clearance() {
    let world = corridor(2.0);
    let cfg = GuidanceConfig::default();
    // Far down the corridor: straight there at cruise speed, facing it.
    let pose = Pose2::new(0.0, 0.0, 0.0);
    let (cmd, _) = step(
        &world,
        pose,
        GuidanceMode::TowardWaypoint {
            world_m: [10.0, 0.0],
        },
    );
    assert!(
        (speed(&cmd) - 0.4).abs() < 0.01 && cmd.velocity_world_m_s[0] > 0.39,
        "{cmd:?}"
    );
    assert!(angle_close(cmd.yaw_rad.unwrap(), 0.0, 1e-3));
    // A waypoint behind the wall 0.6 m away: the approach is held to what the guard allows.
    let pose = Pose2::new(0.0, 0.4, 0.5);
    let (cmd, _) = step(
        &world,
        pose,
        GuidanceMode::TowardWaypoint {
            world_m: [1.0, 3.0],
        },
    );
    let toward_wall = cmd.velocity_world_m_s[1];
    println!("waypoint behind the wall: {cmd:?}");
    assert!(
        toward_wall <= cfg.approach_rate_1_s * (0.6 - cfg.r_min_m()) + 1e-3,
        "{toward_wall}"
    );
    assert!(cmd.decision.guard != Guard::Clear || toward_wall <= 0.0);
    assert!(
        matches!(cmd.decision.outcome, Outcome::TowardWaypoint { distance_m } if (distance_m - 2.7857).abs() < 1e-3)
    );
}

#[test]
fn size_of_the_guidance_state() {
    let s = std::mem::size_of::<Guidance<64>>();
    println!("Guidance<64>: {s} bytes");
    assert!(s <= 16 * 1024, "{s}");
}

#[test]
fn a_single_wall_is_followed_forward_at_about_r_goal() {
    // Seed 002, Fig. 3: along a straight wall the field moves the vehicle forward and corrects
    // its distance. The wall's oblique beams pull toward it (eq. 1), so the distance settles a
    // little inside r_goal (1.2 m): between 0.9 m and 1.2 m.
    let world = vec![wall((-50.0, -1.2), (50.0, -1.2))];
    for (distance, toward_wall) in [
        (1.8f32, true),
        (1.5, true),
        (1.2, true),
        (0.9, false),
        (0.7, false),
    ] {
        let c = wall_follow(&world, Pose2::new(0.0, distance - 1.2, 0.0));
        let [vx, vy] = c.velocity_world_m_s;
        println!("{distance} m from the wall: v = ({vx:.3}, {vy:.3})");
        assert!(vx > 0.2, "{distance}: {vx}");
        assert_eq!(vy < 0.0, toward_wall, "{distance}: {vy}");
        assert!(matches!(
            c.decision.outcome,
            Outcome::WallFollow(HeadingRule::FollowWall { gap: None, .. })
        ));
    }
}

#[test]
fn a_corridor_across_the_nose_is_still_flown_along() {
    // A vehicle that does not turn to its heading (an all-round lidar needs no turning) sees
    // the corridor's walls ahead of and behind it: it still keeps to the middle and moves
    // along the corridor, never toward a wall.
    let world = corridor(2.0);
    for yaw in [PI / 2.0, -PI / 2.0, 2.0, PI] {
        for y in [-0.3f32, 0.0, 0.3] {
            let cmd = wall_follow(&world, Pose2::new(0.0, y, yaw));
            let [vx, vy] = cmd.velocity_world_m_s;
            println!("yaw {yaw:.2} y {y:+.1}: v = ({vx:.3}, {vy:.3})");
            assert!(cmd.decision.centred, "{:?}", cmd.decision);
            assert!((cmd.decision.free_width_m.unwrap() - 2.0).abs() < 0.01);
            assert!(vx.abs() >= 0.39, "along the corridor: {vx}");
            assert!((vy + y).abs() < 1e-3, "toward the middle: {vy}");
        }
    }
}

#[test]
fn a_wall_that_vanishes_from_the_scan_is_remembered_until_the_vehicle_moves_on() {
    // A wall 0.45 m to the right (inside r_min), seen once; the next scans lose it, as a thin
    // wall's end seen edge-on is lost, while the waypoint lies straight through it.
    let seen_from = Pose2::new(0.0, 0.0, 0.0);
    let far = wall((-5.0, 3.0), (5.0, 3.0));
    let at = |world: &[Seg], pose: Pose2, stamp_s: f64| {
        let mut s = look(world, pose);
        s.stamp_s = stamp_s;
        s
    };
    let seen = at(&[far, wall((-5.0, -0.45), (5.0, -0.45))], seen_from, 10.0);
    let through = GuidanceMode::TowardWaypoint {
        world_m: [0.0, -3.0],
    };
    // The velocity toward the lost wall (world -y) a scan at `lost_at_s` from `x` m along it
    // asks for.
    let fly = |memory_s: f32, hold_s: f32, x: f32, lost_at_s: f64| {
        let cfg = GuidanceConfig {
            obstacle_memory_s: memory_s,
            obstacle_hold_s: hold_s,
            ..GuidanceConfig::default()
        };
        let mut g = Guidance::<64>::new(cfg).unwrap();
        g.step(&seen, seen_from, through);
        let pose = Pose2::new(x, 0.0, 0.0);
        g.step(&at(&[far], pose, lost_at_s), pose, through)
            .velocity_world_m_s[1]
    };
    let cruise = GuidanceConfig::default().cruise_speed_m_s;
    let toward = |v: f32| -v;
    // Remembered: no approach at all (the wall is inside r_min)...
    assert!(toward(fly(1.0, 10.0, 0.0, 10.2)) <= 1e-4);
    // ...and after the memory's second too, while the vehicle has stayed where it saw it
    // (lingering in a doorway does not pass the jamb)...
    assert!(toward(fly(1.0, 10.0, 0.0, 13.0)) <= 1e-4);
    assert!(toward(fly(1.0, 10.0, 0.3, 13.0)) <= 1e-4);
    // ...but not once it has moved on by more than its stopping distance (0.5 m; the waypoint
    // then lies a little behind, so not all of the cruise speed is toward it), nor after the
    // hold.
    assert!(toward(fly(1.0, 10.0, 0.8, 13.0)) > 0.9 * cruise);
    assert!((toward(fly(1.0, 10.0, 0.0, 20.5)) - cruise).abs() < 1e-3);
    // Within the memory's second it counts wherever the vehicle is; with no memory, never.
    assert!(toward(fly(1.0, 10.0, 0.8, 10.2)) <= 1e-4);
    assert!((toward(fly(0.0, 0.0, 0.0, 10.2)) - cruise).abs() < 1e-3);
    // A clock that runs backwards starts the memory afresh.
    assert!((toward(fly(1.0, 10.0, 0.0, 9.0)) - cruise).abs() < 1e-3);
}
