//! Matchers against scans ray-cast from known poses in known rooms: the answer is exact.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::matching::{
    MatchConfig, MatchError, MatchStatus, MatcherKind, ScanMatcher, UNOBSERVED_VARIANCE,
};
use plumbline_core::scan::{Beam, Scan};
use proptest::prelude::*;
use synthetic::{corridor, room, scan, Seg};

mod synthetic;

fn matcher<const N: usize>(kind: MatcherKind) -> ScanMatcher<N> {
    ScanMatcher::new(MatchConfig::with_kind(kind))
}

/// Matches the scan at `b` against the scan at `a` and returns (error m, error rad) vs truth.
fn error_of(
    kind: MatcherKind,
    world: &[Seg],
    a: Pose2,
    b: Pose2,
    noise: f32,
    seed: u64,
) -> (f32, f32) {
    let mut m = matcher::<360>(kind);
    m.set_reference(&scan(world, a, 360, std::f32::consts::TAU, noise, seed))
        .unwrap();
    let r = m
        .match_scan(
            &scan(world, b, 360, std::f32::consts::TAU, noise, seed + 1),
            Pose2::IDENTITY,
        )
        .unwrap();
    let truth = a.between(b);
    truth.distance_to(r.motion)
}

#[test]
fn every_matcher_recovers_a_small_motion_in_the_room() {
    let a = Pose2::new(0.3, -0.4, 0.1);
    let b = Pose2::new(0.38, -0.35, 0.13);
    for kind in MatcherKind::ALL {
        let (et, er) = error_of(kind, &room(), a, b, 0.0, 1);
        // The paper's method is translation-only: it cannot remove the 0.03 rad turn. Point-to-point
        // ICP pairs points that are not the same spot on the wall: a known bias of a few mm and
        // a few mrad at 1-degree beams, which moves with the search details.
        let (tol_t, tol_r) = match kind {
            MatcherKind::IclPaper => (0.06, 0.031),
            MatcherKind::Icp => (0.01, 0.006),
            _ => (0.005, 0.002),
        };
        assert!(et < tol_t && er < tol_r, "{}: {et} m {er} rad", kind.name());
    }
}

#[test]
fn icl_handles_a_larger_motion_with_noise_better_than_a_centimetre() {
    let a = Pose2::new(-0.5, 0.2, 0.0);
    let b = Pose2::new(-0.25, 0.3, 0.15);
    for seed in 0..5 {
        let (et, er) = error_of(MatcherKind::Icl, &room(), a, b, 0.01, seed);
        assert!(et < 0.01 && er < 0.005, "seed {seed}: {et} m {er} rad");
    }
}

#[test]
fn icl_reports_convergence_inliers_and_a_small_covariance() {
    let (a, b) = (Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.05, 0.02, 0.02));
    let mut m = matcher::<360>(MatcherKind::Icl);
    m.set_reference(&scan(&room(), a, 360, std::f32::consts::TAU, 0.01, 3))
        .unwrap();
    let r = m
        .match_scan(
            &scan(&room(), b, 360, std::f32::consts::TAU, 0.01, 4),
            Pose2::IDENTITY,
        )
        .unwrap();
    let q = r.quality;
    assert_eq!(q.status, plumbline_core::matching::MatchStatus::Converged);
    assert!(q.inlier_ratio > 0.9, "{q:?}");
    assert!(q.degenerate_direction.is_none());
    assert!(q.rms_residual_m < 0.03, "{q:?}");
    let sx = r.covariance[0][0].sqrt();
    assert!(sx > 1e-5 && sx < 0.01, "sigma x {sx}");
}

#[test]
fn a_corridor_is_reported_degenerate_along_its_axis_and_keeps_the_guess_there() {
    let a = Pose2::new(0.0, 0.0, 0.0);
    let b = Pose2::new(0.4, 0.1, 0.05);
    let mut m = matcher::<360>(MatcherKind::Icl);
    m.set_reference(&scan(&corridor(), a, 360, std::f32::consts::TAU, 0.0, 1))
        .unwrap();
    let guess = Pose2::new(0.25, 0.0, 0.0);
    let r = m
        .match_scan(
            &scan(&corridor(), b, 360, std::f32::consts::TAU, 0.0, 2),
            guess,
        )
        .unwrap();
    let v = r
        .quality
        .degenerate_direction
        .expect("corridor must be degenerate");
    assert!(v.x.abs() > 0.99, "direction {v:?}");
    // Across the corridor and in rotation the scans decide; along it the guess stays.
    assert!(
        (r.motion.y - 0.1).abs() < 0.01 && (r.motion.theta - 0.05).abs() < 0.01,
        "{:?}",
        r.motion
    );
    assert!((r.motion.x - 0.25).abs() < 0.02, "{:?}", r.motion);
    assert!(r.covariance[0][0] >= UNOBSERVED_VARIANCE * 0.9);
    assert!(r.covariance[1][1] < 1e-2);
    // What a filter fuses: nothing along the axis, the same variance across it and in rotation.
    let o = r.observed_covariance;
    let across = v.perp();
    let var_across = across.x * across.x * o[0][0]
        + 2.0 * across.x * across.y * o[0][1]
        + across.y * across.y * o[1][1];
    assert!(o[0][0] < 1e-2, "{o:?}");
    assert!(
        var_across > 0.0 && (var_across - r.covariance[1][1]).abs() < 0.01 * var_across,
        "{var_across} against {:?}",
        r.covariance
    );
    assert_eq!(o[2][2], r.covariance[2][2]);
}

#[test]
fn a_walking_person_is_rejected_and_does_not_pull_the_estimate() {
    let mut with_person = room();
    // A 0.4 m "person" box that moves 0.3 m between the two revolutions.
    let person = |cx: f32| {
        let p = [
            (cx - 0.2, -1.0),
            (cx + 0.2, -1.0),
            (cx + 0.2, -0.6),
            (cx - 0.2, -0.6),
        ];
        (0..4).map(move |i| {
            (
                Vec2::new(p[i].0, p[i].1),
                Vec2::new(p[(i + 1) % 4].0, p[(i + 1) % 4].1),
            )
        })
    };
    let world_a: Vec<Seg> = with_person.iter().copied().chain(person(0.8)).collect();
    with_person.extend(person(1.1));
    let (a, b) = (Pose2::IDENTITY, Pose2::new(0.02, 0.01, 0.0));
    let mut m = matcher::<360>(MatcherKind::Icl);
    m.set_reference(&scan(&world_a, a, 360, std::f32::consts::TAU, 0.005, 1))
        .unwrap();
    let r = m
        .match_scan(
            &scan(&with_person, b, 360, std::f32::consts::TAU, 0.005, 2),
            Pose2::IDENTITY,
        )
        .unwrap();
    let (et, er) = a.between(b).distance_to(r.motion);
    assert!(et < 0.01 && er < 0.005, "{et} {er}");
}

#[test]
fn bad_scans_give_errors_not_panics_or_nans() {
    let mut m = matcher::<360>(MatcherKind::Icl);
    let good: Scan<360> = scan(&room(), Pose2::IDENTITY, 360, std::f32::consts::TAU, 0.0, 1);
    assert_eq!(
        m.match_scan(&good, Pose2::IDENTITY).unwrap_err(),
        MatchError::NoReference
    );

    let empty: Scan<360> = Scan::new(0.0);
    assert!(matches!(
        m.set_reference(&empty)
            .and_then(|_| m.match_scan(&good, Pose2::IDENTITY)),
        Err(MatchError::TooFewPoints { .. })
    ));

    let mut all_invalid: Scan<360> = Scan::new(0.0);
    let mut nan: Scan<360> = Scan::new(0.0);
    for i in 0..360 {
        let a = i as f32 * 0.0174;
        all_invalid.push(Beam::invalid(a)).unwrap();
        nan.push(Beam {
            valid: true,
            ..Beam::new(a, f32::NAN)
        })
        .unwrap();
    }
    m.set_reference(&good).unwrap();
    assert!(matches!(
        m.match_scan(&all_invalid, Pose2::IDENTITY),
        Err(MatchError::TooFewPoints { .. })
    ));
    assert!(matches!(
        m.match_scan(&nan, Pose2::IDENTITY),
        Err(MatchError::TooFewPoints { .. })
    ));
    assert_eq!(
        m.match_scan(
            &good,
            Pose2 {
                x: f32::NAN,
                y: 0.0,
                theta: 0.0
            }
        )
        .unwrap_err(),
        MatchError::NonFiniteGuess
    );

    // Two identical scans: zero motion, exactly.
    let r = m.match_scan(&good, Pose2::IDENTITY).unwrap();
    assert!(
        r.motion.translation().norm() < 1e-4 && r.motion.theta.abs() < 1e-4,
        "{:?}",
        r.motion
    );
    assert!(r.covariance.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn scans_that_do_not_overlap_fail_cleanly() {
    let mut m = matcher::<360>(MatcherKind::Icl);
    m.set_reference(&scan(
        &room(),
        Pose2::IDENTITY,
        360,
        std::f32::consts::TAU,
        0.0,
        1,
    ))
    .unwrap();
    // A hall whose walls are all 8-10 m away: no point lies near any reference point.
    let c = [(-9.0, -8.0), (9.0, -8.0), (9.0, 8.0), (-9.0, 8.0)];
    let hall: Vec<Seg> = (0..4)
        .map(|i| {
            (
                Vec2::new(c[i].0, c[i].1),
                Vec2::new(c[(i + 1) % 4].0, c[(i + 1) % 4].1),
            )
        })
        .collect();
    let r = m.match_scan(
        &scan(&hall, Pose2::IDENTITY, 360, std::f32::consts::TAU, 0.0, 2),
        Pose2::IDENTITY,
    );
    assert!(
        matches!(r, Err(MatchError::TooFewCorrespondences { .. })),
        "{r:?}"
    );
}

#[test]
fn a_wrong_heading_guess_is_recovered_by_the_heading_search() {
    let s: Scan<360> = scan(&room(), Pose2::IDENTITY, 360, std::f32::consts::TAU, 0.0, 1);
    let mut m = matcher::<360>(MatcherKind::Icl);
    m.set_reference(&s).unwrap();
    // The same scan, but the guess says the vehicle turned 54 degrees: outside the iteration's
    // basin (see the next test), inside the search's.
    let r = m.match_scan(&s, Pose2::new(0.0, 0.0, 0.95)).unwrap();
    assert!(r.quality.recovered, "{:?}", r.quality);
    let (et, er) = Pose2::IDENTITY.distance_to(r.motion);
    assert!(et < 1e-3 && er < 1e-3, "{:?}", r.motion);
}

#[test]
fn without_recovery_a_wrong_guess_shows_in_the_quality_report() {
    let s: Scan<360> = scan(&room(), Pose2::IDENTITY, 360, std::f32::consts::TAU, 0.0, 1);
    let mut m = ScanMatcher::<360>::new(MatchConfig {
        recovery: false,
        ..MatchConfig::default()
    });
    m.set_reference(&s).unwrap();
    match m.match_scan(&s, Pose2::new(0.0, 0.0, 0.95)) {
        Ok(r) => {
            let q = r.quality;
            let flagged = q.status != MatchStatus::Converged || q.inlier_ratio < 0.6;
            assert!(flagged && q.rms_residual_m > 0.05, "{q:?}");
        }
        Err(e) => assert!(
            matches!(
                e,
                MatchError::TooFewCorrespondences { .. } | MatchError::Diverged
            ),
            "{e:?}"
        ),
    }
}

/// A search that a low inlier ratio alone started and that found nothing better makes a matcher
/// with `recovery_rest_matches` skip the search on that many sparse matches after it: two
/// thirds of the room hidden behind a box around the lidar, matched from a guess 0.4 m off,
/// pairs 29 of its points, and only the search finds the 110 that pair at the true pose.
#[test]
fn after_a_fruitless_search_sparse_matches_rest() {
    let tau = std::f32::consts::TAU;
    let mut boxed = room();
    let corners = [(-0.3, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.3, 0.5)];
    boxed.extend(
        corners
            .windows(2)
            .map(|w| (Vec2::new(w[0].0, w[0].1), Vec2::new(w[1].0, w[1].1))),
    );
    let reference: Scan<360> = scan(&room(), Pose2::IDENTITY, 360, tau, 0.0, 1);
    let hidden: Scan<360> = scan(&boxed, Pose2::IDENTITY, 360, tau, 0.0, 2);
    for (rest, expected) in [(0, [true; 4]), (3, [false, false, false, true])] {
        let mut m = ScanMatcher::<360>::new(MatchConfig {
            recovery_rest_matches: rest,
            ..MatchConfig::default()
        });
        m.set_reference(&reference).unwrap();
        // From the true pose the search finds that pose again: nothing better.
        let q = m.match_scan(&hidden, Pose2::IDENTITY).unwrap().quality;
        assert!(q.inlier_ratio < 0.5 && !q.recovered, "{q:?}");
        let rescued = expected.map(|_| {
            let r = m.match_scan(&hidden, Pose2::new(0.4, 0.0, 0.0)).unwrap();
            assert_eq!(r.quality.status, MatchStatus::Converged);
            r.quality.recovered
        });
        assert_eq!(rescued, expected, "rest {rest}");
    }
}

#[test]
fn promote_current_matches_a_fresh_reference() {
    let poses = [
        Pose2::IDENTITY,
        Pose2::new(0.05, 0.0, 0.02),
        Pose2::new(0.1, 0.03, 0.05),
    ];
    let scans: Vec<Scan<360>> = poses
        .iter()
        .enumerate()
        .map(|(i, &p)| scan(&room(), p, 360, std::f32::consts::TAU, 0.0, i as u64))
        .collect();
    let mut chained = matcher::<360>(MatcherKind::Icl);
    chained.set_reference(&scans[0]).unwrap();
    chained.match_scan(&scans[1], Pose2::IDENTITY).unwrap();
    chained.promote_current();
    let a = chained.match_scan(&scans[2], Pose2::IDENTITY).unwrap();
    let mut fresh = matcher::<360>(MatcherKind::Icl);
    fresh.set_reference(&scans[1]).unwrap();
    let b = fresh.match_scan(&scans[2], Pose2::IDENTITY).unwrap();
    assert_eq!(a.motion, b.motion);
}

#[test]
fn state_sizes_fit_the_seed_controller() {
    let s360 = std::mem::size_of::<ScanMatcher<360>>();
    let s1440 = std::mem::size_of::<ScanMatcher<1440>>();
    println!("ScanMatcher<360>: {s360} bytes, ScanMatcher<1440>: {s1440} bytes");
    assert!(s360 <= 16 * 1024, "{s360}");
    assert!(s1440 <= 64 * 1024, "{s1440}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Any modest motion in the room, any seed: ICL recovers it to a centimetre and a third of a degree.
    #[test]
    fn icl_recovers_random_motions(x in -0.15f32..0.15, y in -0.15f32..0.15, th in -0.1f32..0.1, seed in 0u64..1000) {
        let a = Pose2::new(0.2, -0.3, 0.4);
        let b = a.compose(Pose2::new(x, y, th));
        let (et, er) = error_of(MatcherKind::Icl, &room(), a, b, 0.005, seed);
        prop_assert!(et < 0.01 && er < 0.006, "{} m {} rad", et, er);
    }

    /// 180-degree scans (the benchmark logs' layout) also work, and so does PL-ICP.
    #[test]
    fn half_scans_match_too(x in -0.1f32..0.1, th in -0.05f32..0.05, seed in 0u64..1000) {
        let a = Pose2::new(-1.0, 0.0, 0.0);
        let b = a.compose(Pose2::new(x, 0.02, th));
        for kind in [MatcherKind::Icl, MatcherKind::Plicp] {
            let mut m = matcher::<181>(kind);
            m.set_reference(&scan(&room(), a, 181, std::f32::consts::PI, 0.005, seed)).unwrap();
            let r = m.match_scan(&scan(&room(), b, 181, std::f32::consts::PI, 0.005, seed + 7), Pose2::IDENTITY).unwrap();
            let (et, er) = a.between(b).distance_to(r.motion);
            prop_assert!(et < 0.015 && er < 0.006, "{}: {} m {} rad", kind.name(), et, er);
        }
    }
}

/// A URG-04LX-like scan (667 beams over 240°, 1 cm noise): its beams are 0.36° apart, so at a
/// metre eight neighbours a side span only 5 cm, too short for a line to rise above the noise.
/// Fits must reach their spatial extent, or most points get no line, the match keeps a third of
/// them and falls back to the recovery search (as it did, median 15.6 ms a match in the
/// simulator's room).
#[test]
fn a_dense_noisy_scan_still_gets_its_lines() {
    // The room at half size, so that most walls are within a metre or so.
    let world: Vec<Seg> = room().iter().map(|&(p, q)| (p * 0.5, q * 0.5)).collect();
    let fov = 240f32.to_radians();
    let a = Pose2::new(0.1, -0.15, 0.1);
    let b = Pose2::new(0.13, -0.14, 0.12);
    let mut m = matcher::<1440>(MatcherKind::Icl);
    m.set_reference(&scan(&world, a, 667, fov, 0.01, 41))
        .unwrap();
    let r = m
        .match_scan(&scan(&world, b, 667, fov, 0.01, 42), Pose2::IDENTITY)
        .unwrap();
    let (dt, dr) = a.between(b).distance_to(r.motion);
    assert!(r.quality.inlier_ratio > 0.7, "{:?}", r.quality);
    assert!(!r.quality.recovered, "{:?}", r.quality);
    assert!(dt < 0.01 && dr < 0.005, "{dt} m {dr} rad: {:?}", r.motion);
}

/// A room 6 m wide seen by a noisy 4 m lidar from its middle, far from its ends: only the side
/// walls are in range. Their noisy normals lend the axis a little information (the eigenvalue
/// test alone does not call it degenerate); with the localizability check, too few points face
/// the axis, so it is degenerate and the guess is kept along it.
#[test]
fn noisy_side_walls_do_not_measure_motion_along_them() {
    let walls = vec![
        (Vec2::new(-50.0, -3.0), Vec2::new(50.0, -3.0)),
        (Vec2::new(-50.0, 3.0), Vec2::new(50.0, 3.0)),
    ];
    let (a, b) = (Pose2::IDENTITY, Pose2::new(0.15, 0.02, 0.01));
    let mut unchecked_not_degenerate = 0;
    for seed in 0..20u64 {
        let run = |check: f32| {
            let mut m = ScanMatcher::<360>::new(MatchConfig {
                localizability_check_below: check,
                degenerate_point_passes: 0,
                ..MatchConfig::default()
            });
            let tau = std::f32::consts::TAU;
            m.set_reference(&synthetic::scan_within(
                &walls,
                a,
                360,
                tau,
                0.035,
                2 * seed,
                4.0,
            ))
            .unwrap();
            let current = synthetic::scan_within(&walls, b, 360, tau, 0.035, 2 * seed + 1, 4.0);
            m.match_scan(&current, b).unwrap()
        };
        let checked = run(0.25);
        let v = checked
            .quality
            .degenerate_direction
            .unwrap_or_else(|| panic!("seed {seed}: the axis must be degenerate"));
        assert!(v.x.abs() > 0.99, "seed {seed}: direction {v:?}");
        assert!(
            (checked.motion.x - b.x).abs() < 1e-3,
            "seed {seed}: along the axis the guess stays: {:?}",
            checked.motion
        );
        assert!(
            (checked.motion.y - b.y).abs() < 0.02,
            "{:?}",
            checked.motion
        );
        unchecked_not_degenerate += usize::from(run(0.0).quality.degenerate_direction.is_none());
    }
    // Without the check the noise passes the eigenvalue test on most seeds.
    assert!(
        unchecked_not_degenerate >= 10,
        "{unchecked_not_degenerate} of 20"
    );
}
