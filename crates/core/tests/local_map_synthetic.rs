//! The local map against ray-cast scans from known poses: refinement finds the true pose, keeps
//! the prior where the walls say nothing, and the mapped odometry drifts less than the plain one.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::matching::local_map::{
    correction_is_plausible, map_age, refine, relocalize, Declined, LineMap, LineMapConfig,
    MapCell, MappedOdometry, RefineConfig, RefineRefusal, RelocalizeConfig, Sym3,
};
use plumbline_core::matching::{LidarOdometry, OdometryConfig, PreparedScan};
use plumbline_core::scan::Scan;
use std::f32::consts::TAU;
use synthetic::{corridor, room, scan, Seg};

mod synthetic;

/// The valid points of a 360-beam scan from `pose`, in its own frame.
fn points(world: &[Seg], pose: Pose2, seed: u64) -> Vec<Vec2> {
    let s: Scan<360> = scan(world, pose, 360, TAU, 0.01, seed);
    let mut prepared = PreparedScan::<360>::default();
    prepared.load(&s).unwrap();
    prepared.points().to_vec()
}

/// A map of `world` made from scans at `poses`, inserted at their true poses at stamp 0.
fn mapped<'a>(cells: &'a mut [MapCell], world: &[Seg], poses: &[Pose2]) -> LineMap<'a> {
    let mut map = LineMap::new(cells, LineMapConfig::default()).unwrap();
    for (k, &pose) in poses.iter().enumerate() {
        for p in points(world, pose, 100 + k as u64) {
            map.insert(pose.transform(p), 0);
        }
    }
    map
}

/// 1 m and 1 rad standard deviation: enough to hold a direction the walls leave free.
fn weak_prior() -> Sym3 {
    Sym3 {
        xx: 1.0,
        yy: 1.0,
        tt: 1.0,
        ..Sym3::default()
    }
}

#[test]
fn refinement_finds_the_true_pose_from_an_offset_guess() {
    let world = room();
    let mut cells = vec![MapCell::default(); 64 * 64];
    let survey = [
        Pose2::new(0.0, 0.0, 0.0),
        Pose2::new(1.0, -0.5, 0.4),
        Pose2::new(-1.5, 0.2, -0.8),
    ];
    let map = mapped(&mut cells, &world, &survey);
    let truth = Pose2::new(0.6, 0.3, 0.2);
    let guess = Pose2::new(0.68, 0.25, 0.23);
    let pts = points(&world, truth, 7);
    let refined = refine(&map, &pts, guess, weak_prior(), &RefineConfig::default()).unwrap();
    let (d, a) = truth.distance_to(refined.pose);
    assert!(d < 0.01 && a < 0.003, "{d} m {a} rad: {refined:?}");
    assert!(refined.matched as usize > pts.len() / 2, "{refined:?}");
}

#[test]
fn along_a_corridor_the_prior_holds_and_across_it_the_walls_correct() {
    let world = corridor();
    let mut cells = vec![MapCell::default(); 128 * 128];
    let survey = [Pose2::new(-1.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)];
    let map = mapped(&mut cells, &world, &survey);
    let truth = Pose2::new(0.0, 0.1, 0.0);
    let guess = Pose2::new(0.2, 0.16, 0.02);
    let pts = points(&world, truth, 8);
    let refined = refine(&map, &pts, guess, weak_prior(), &RefineConfig::default()).unwrap();
    assert!((refined.pose.y - truth.y).abs() < 0.01, "{refined:?}");
    assert!(refined.pose.theta.abs() < 0.003, "{refined:?}");
    assert!((refined.pose.x - guess.x).abs() < 0.01, "{refined:?}");
}

#[test]
fn an_empty_map_or_a_scan_elsewhere_is_refused() {
    let world = room();
    let mut cells = vec![MapCell::default(); 64 * 64];
    let empty = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
    let pts = points(&world, Pose2::IDENTITY, 9);
    let r = refine(
        &empty,
        &pts,
        Pose2::IDENTITY,
        weak_prior(),
        &RefineConfig::default(),
    );
    assert!(
        matches!(r, Err(RefineRefusal::TooFewMatched { matched: 0, .. })),
        "{r:?}"
    );

    let mut cells = vec![MapCell::default(); 64 * 64];
    let map = mapped(&mut cells, &world, &[Pose2::IDENTITY]);
    let far = Pose2::new(5.0, 4.0, 1.0);
    let r = refine(&map, &pts, far, weak_prior(), &RefineConfig::default());
    assert!(r.is_err(), "{r:?}");
}

/// Laps of the room on a circle, scan every 5 cm: the plain odometry's heading error is a random
/// walk over keyframes; the mapped one keeps coming back to the same walls.
#[test]
fn mapped_odometry_drifts_less_than_scan_to_keyframe_odometry() {
    let world = room();
    let mut plain = Box::new(LidarOdometry::<360>::new(OdometryConfig::default()));
    let mut cells = vec![MapCell::default(); 64 * 64];
    let map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
    let mut mapped = Box::new(MappedOdometry::<360>::new(
        OdometryConfig::default(),
        map,
        RefineConfig::default(),
        None,
    ));
    // An ellipse that keeps 0.2 m or more from the pillar and 0.6 m from the walls.
    let at = |phase: f32| Pose2::new(2.0 * phase.cos(), 1.4 * phase.sin(), phase + TAU / 4.0);
    let start = at(0.0);
    let (mut worst_plain, mut worst_mapped) = (0.0f32, 0.0f32);
    let steps = 600;
    for k in 0..=steps {
        let phase = TAU * 3.0 * k as f32 / steps as f32;
        let truth = at(phase);
        let s: Scan<360> = scan(&world, truth, 360, TAU, 0.02, 1000 + k as u64);
        plain.update(&s, None);
        mapped.update(&s, None);
        let expected = start.between(truth);
        worst_plain = worst_plain.max(expected.distance_to(plain.pose()).0);
        worst_mapped = worst_mapped.max(expected.distance_to(mapped.pose()).0);
    }
    println!("worst position error: plain {worst_plain:.4} m, mapped {worst_mapped:.4} m");
    assert!(worst_mapped < 0.02, "mapped {worst_mapped}");
    assert!(
        worst_mapped < 0.7 * worst_plain,
        "mapped {worst_mapped} plain {worst_plain}"
    );
}

/// A 10 cm, 2.3° correction is more than a confident matcher (1 cm, 0.1°) drifts in one keyframe,
/// but well within what it drifts in a hundred: the walls' age decides.
#[test]
fn a_large_correction_counts_only_against_walls_mapped_long_ago() {
    let world = room();
    let mut cells = vec![MapCell::default(); 64 * 64];
    let map = mapped(
        &mut cells,
        &world,
        &[Pose2::IDENTITY, Pose2::new(1.0, 0.0, 0.5)],
    );
    let truth = Pose2::new(0.3, 0.2, 0.1);
    let pts = points(&world, truth, 21);
    let guess = Pose2::new(0.4, 0.2, 0.14);
    assert_eq!(map_age(&map, &pts, guess, 10, 0.2), Some(10.0));
    assert_eq!(map_age(&map, &pts, guess, 0, 0.2), Some(1.0));
    assert_eq!(map_age(&map, &[], guess, 10, 0.2), None);
    let refined = refine(&map, &pts, guess, weak_prior(), &RefineConfig::default()).unwrap();
    assert!(truth.distance_to(refined.pose).0 < 0.01, "{refined:?}");
    let matcher = Sym3 {
        xx: 1e4,
        yy: 1e4,
        tt: 3e5,
        ..Sym3::default()
    };
    let max_d2 = RefineConfig::default().max_correction_d2;
    let young = correction_is_plausible(guess, refined.pose, &matcher, 1.0, max_d2);
    assert!(
        matches!(young, Err(RefineRefusal::Implausible { d2 }) if d2 > max_d2),
        "{young:?}"
    );
    assert_eq!(
        correction_is_plausible(guess, refined.pose, &matcher, 100.0, max_d2),
        Ok(())
    );
}

/// Back in a mapped room with half a metre and two degrees of drift: too far for the refinement,
/// found by the search, then polished by the refinement.
#[test]
fn relocalization_takes_out_drift_beyond_the_refinement_s_reach() {
    // The room at three times its size: in the small one a few tenths of a degree move no wall
    // by more than the search's inlier distance, so heading is not resolved to a step.
    let world: Vec<Seg> = room().iter().map(|&(a, b)| (a * 3.0, b * 3.0)).collect();
    let mut cells = vec![MapCell::default(); 128 * 128];
    let survey: Vec<Pose2> = (0..12)
        .map(|k| Pose2::new(-6.0 + 1.2 * k as f32, 0.4 * (k % 3) as f32, 0.5 * k as f32))
        .collect();
    let map = mapped(&mut cells, &world, &survey);
    let truth = Pose2::new(2.4, 1.2, 0.3);
    let drifted = Pose2::new(2.85, 0.95, 0.335);
    let pts = points(&world, truth, 11);
    let config = RelocalizeConfig::default();
    let now = config.min_age;
    let found = relocalize(&map, &pts, drifted, now, &config).unwrap();
    let (d, a) = truth.distance_to(found);
    assert!(d < 0.1 && a < 0.015, "{d} m {a} rad: {found:?}");
    let polished = refine(&map, &pts, found, weak_prior(), &RefineConfig::default()).unwrap();
    let (d, a) = truth.distance_to(polished.pose);
    assert!(d < 0.01 && a < 0.003, "{d} m {a} rad: {polished:?}");
}

#[test]
fn relocalization_declines_young_maps_and_keeps_a_corridor_s_axis() {
    let world = room();
    let mut cells = vec![MapCell::default(); 64 * 64];
    let map = mapped(&mut cells, &world, &[Pose2::IDENTITY]);
    let pts = points(&world, Pose2::IDENTITY, 12);
    let config = RelocalizeConfig::default();
    // Walls mapped at stamp 0 are not old yet one keyframe later.
    let r = relocalize(&map, &pts, Pose2::new(0.4, 0.0, 0.0), 1, &config);
    assert!(r.is_err(), "{r:?}");
    assert_eq!(
        relocalize(&map, &[], Pose2::IDENTITY, 100, &config),
        Err(Declined::NothingToSearch)
    );

    // In a corridor every pose along the axis fits: the search fixes the offset across it and
    // the heading, and stays where the guess was along it.
    let world = corridor();
    let mut cells = vec![MapCell::default(); 128 * 128];
    let map = mapped(
        &mut cells,
        &world,
        &[Pose2::new(-1.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)],
    );
    let truth = Pose2::new(0.0, 0.0, 0.0);
    let drifted = Pose2::new(0.3, 0.4, 0.03);
    let found = relocalize(&map, &points(&world, truth, 13), drifted, 100, &config).unwrap();
    assert!(
        found.y.abs() < 0.1 && found.theta.abs() < 0.015,
        "{found:?}"
    );
    assert!((found.x - drifted.x).abs() < 0.15, "{found:?}");
}

/// Driving down a corridor whose walls behind were mapped long ago and whose walls ahead only
/// now: every pose further back puts more of the scan on old walls, so the score rises off the
/// window's edge. The search must not take that slope for a peak and jump back along the
/// corridor (it did, 1 m at a time, in the simulator's office).
#[test]
fn relocalization_does_not_slide_back_onto_old_walls_along_a_corridor() {
    let world = corridor();
    let mut cells = vec![MapCell::default(); 256 * 256];
    let mut map = LineMap::new(&mut cells, LineMapConfig::default()).unwrap();
    let config = RelocalizeConfig {
        // Only the slope test stands between the search and the jump.
        min_gain: 1.2,
        ..RelocalizeConfig::default()
    };
    let now = config.min_age + 10;
    for k in 0..=24u64 {
        let pose = Pose2::new(k as f32 - 12.0, 0.0, 0.0);
        for p in points(&world, pose, 300 + k) {
            let w = pose.transform(p);
            map.insert(w, if w.x < -1.0 { 0 } else { now });
        }
    }
    let truth = Pose2::IDENTITY;
    let pts = points(&world, truth, 7);
    let found = relocalize(&map, &pts, truth, now, &config);
    if let Ok(pose) = found {
        assert!(truth.distance_to(pose).0 < 0.15, "{pose:?}");
    }
}

/// What the map costs an embedded user: one `MapCell` per cell of the caller's buffer.
#[test]
fn a_map_cell_stays_small() {
    let cell = std::mem::size_of::<MapCell>();
    println!(
        "MapCell {cell} B; 64 x 64 cells (16 m at 0.25 m) = {} KB",
        cell * 4096 / 1024
    );
    assert!(cell <= 64, "{cell}");
}
