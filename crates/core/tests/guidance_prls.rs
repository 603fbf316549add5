//! Properties of the wall segments and of the guidance command on random scenes (cases drawn
//! from the workspace's fixed seed, `.cargo/config.toml`).

#[allow(dead_code)] // each test binary uses its own share of the shared scenes
mod synthetic;

use plumbline_core::geom::{normalize_angle, Pose2, Vec2};
use plumbline_core::guidance::guard::respects_every_hit;
use plumbline_core::guidance::{Guidance, GuidanceConfig, GuidanceMode, WallSegments};
use plumbline_core::scan::{Beam, Scan};
use proptest::prelude::*;
use std::f32::consts::{PI, TAU};
use synthetic::{scan_within, Seg};

const BEAMS: usize = 360;

/// The line with unit normal at `normal_rad` and distance `distance_m` from the origin, as a
/// 40 m wall centred on the foot of the normal.
fn line(normal_rad: f32, distance_m: f32) -> Seg {
    let n = Vec2::new(normal_rad.cos(), normal_rad.sin());
    let foot = n * distance_m;
    (foot + n.perp() * 20.0, foot - n.perp() * 20.0)
}

fn extract(world: &[Seg], noise_m: f32, seed: u64) -> (Scan<BEAMS>, WallSegments<32>) {
    let scan = scan_within(world, Pose2::IDENTITY, BEAMS, TAU, noise_m, seed, 8.0);
    let mut walls = WallSegments::<32>::default();
    walls.extract(&scan, &GuidanceConfig::default());
    (scan, walls)
}

fn on_line(
    normal_rad: f32,
    distance_m: f32,
    seg_normal: f32,
    seg_distance: f32,
    tol_m: f32,
    tol_rad: f32,
) -> bool {
    normalize_angle(seg_normal - normal_rad).abs() < tol_rad
        && (seg_distance - distance_m).abs() < tol_m
}

/// Every segment's ends are its first and last hits, projected on its line: within `tol_m`,
/// or `seam_tol_m` for an end at the sweep's first or last beam, where no hit beyond the seam
/// is there to take a corner's hit over from it.
fn ends_on_the_scan(
    scan: &Scan<BEAMS>,
    walls: &WallSegments<32>,
    tol_m: f32,
    seam_tol_m: f32,
) -> Result<(), TestCaseError> {
    let last_pos = walls.sweep_len() - 1;
    for s in walls.segments() {
        let first = scan.beams()[walls.beam_index(s.first_pos)].point();
        let last = scan.beams()[walls.beam_index(s.last_pos)].point();
        let start_tol = if s.first_pos == 0 { seam_tol_m } else { tol_m };
        let end_tol = if s.last_pos == last_pos {
            seam_tol_m
        } else {
            tol_m
        };
        prop_assert!(
            (s.start_m - first).norm() < start_tol,
            "{:?} vs {:?}",
            s,
            first
        );
        prop_assert!((s.end_m - last).norm() < end_tol, "{:?} vs {:?}", s, last);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Hits on one known line give that line back (twice at most: the sweep may start on it).
    #[test]
    fn points_on_a_line_give_the_line(alpha in -PI..PI, rho in 0.6f32..4.0) {
        let (scan, walls) = extract(&[line(alpha, rho)], 0.0, 1);
        prop_assert!(!walls.segments().is_empty() && walls.segments().len() <= 2, "{:?}", walls.segments());
        for s in walls.segments() {
            prop_assert!(on_line(alpha, rho, s.normal_rad, s.distance_m, 1e-3, 1e-3), "{s:?}");
            prop_assert!(s.rms_residual_m < 1e-3);
        }
        ends_on_the_scan(&scan, &walls, 1e-3, 1e-3)?;
    }

    /// Two walls meeting at a corner: every segment lies on one of them, none straddles it (a
    /// hit within half the line tolerance of the corner may join either wall, hence the
    /// millimetre bounds, and why an end may sit up to half the tolerance off its hit; at the
    /// sweep's seam a corner hit within the whole tolerance stays with the wall it ends).
    #[test]
    fn a_corner_splits_into_two_lines(
        corner_dir in -PI..PI,
        corner_dist in 1.0f32..3.0,
        heading in -PI..PI,
        turn in (PI / 4.0)..(3.0 * PI / 4.0),
    ) {
        let c = Vec2::new(corner_dir.cos(), corner_dir.sin()) * corner_dist;
        let d1 = Vec2::new(heading.cos(), heading.sin());
        let d2 = Vec2::new((heading + turn).cos(), (heading + turn).sin());
        let world = [(c - d1 * 10.0, c), (c, c + d2 * 10.0)];
        // Each wall's line in normal form, as seen from the sensor at the origin.
        let normal_form = |d: Vec2| {
            let mut n = d.perp();
            if c.dot(n) < 0.0 { n = n * -1.0; }
            (n.y.atan2(n.x), c.dot(n))
        };
        let lines = [normal_form(d1), normal_form(d2)];
        prop_assume!(lines.iter().all(|&(_, rho)| rho > 0.5));
        let (scan, walls) = extract(&world, 0.0, 2);
        for s in walls.segments() {
            // Short pieces next to the sweep start are swung most by one corner hit, and so is
            // a wall that ends the sweep, which keeps the corner's hit.
            let at_seam = s.last_pos == walls.sweep_len() - 1;
            let (tol_m, tol_rad) = match (s.points >= 15, at_seam) {
                (true, false) => (5e-3, 5e-3),
                (true, true) => (0.01, 0.01),
                (false, _) => (0.03, 0.1),
            };
            let fits = lines.iter().any(|&(a, r)| on_line(a, r, s.normal_rad, s.distance_m, tol_m, tol_rad));
            prop_assert!(fits && s.rms_residual_m < 0.01, "{s:?} vs {lines:?}");
        }
        ends_on_the_scan(&scan, &walls, 0.025, GuidanceConfig::default().line_tolerance_m)?;
    }

    /// Centimetre range noise: well-populated segments still sit on the true line.
    #[test]
    fn noisy_hits_give_the_line_within_centimetres(alpha in -PI..PI, rho in 0.8f32..3.0, seed in 0u64..1000) {
        let (scan, walls) = extract(&[line(alpha, rho)], 0.01, seed);
        prop_assert!(!walls.segments().is_empty());
        for s in walls.segments().iter().filter(|s| s.points >= 20) {
            prop_assert!(on_line(alpha, rho, s.normal_rad, s.distance_m, 0.02, 0.03), "{s:?}");
        }
        ends_on_the_scan(&scan, &walls, 0.05, 0.05)?;
    }
}

/// A scan of random ranges, some invalid: usually a regular revolution, sometimes a short one
/// with beams in any order, repeated angles or angles that are not numbers.
fn random_scan() -> impl Strategy<Value = Scan<BEAMS>> {
    let range = prop_oneof![4 => (0.1f32..7.0).prop_map(Some), 1 => Just(None)];
    let regular = proptest::collection::vec(range.clone(), BEAMS).prop_map(|ranges| {
        let step = TAU / BEAMS as f32;
        ranges
            .into_iter()
            .enumerate()
            .map(|(i, r)| (-PI + step * i as f32, r))
            .collect::<Vec<_>>()
    });
    let angle = prop_oneof![9 => -7.0f32..7.0, 1 => Just(f32::NAN)];
    let scrambled = proptest::collection::vec((angle, range), 0..BEAMS);
    prop_oneof![3 => regular, 1 => scrambled].prop_map(|beams| {
        let mut s = Scan::new(0.0);
        for (a, r) in beams {
            s.push(r.map_or(Beam::invalid(a), |r| Beam::new(a, r)))
                .unwrap();
        }
        s
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Whatever the scan, pose or mode: a finite command within the speed limit that closes on
    /// no hit faster than the guard allows.
    #[test]
    fn every_command_is_finite_slow_and_clear_of_every_hit(
        scan in random_scan(),
        x in -5.0f32..5.0, y in -5.0f32..5.0, yaw in -PI..PI,
        waypoint in proptest::option::of((-10.0f32..10.0, -10.0f32..10.0)),
    ) {
        let cfg = GuidanceConfig::default();
        let mut g = Guidance::<64>::new(cfg).unwrap();
        let pose = Pose2::new(x, y, yaw);
        let mode = waypoint.map_or(GuidanceMode::WallFollow, |(wx, wy)| GuidanceMode::TowardWaypoint { world_m: [wx, wy] });
        let cmd = g.step(&scan, pose, mode);
        let v_world = Vec2::new(cmd.velocity_world_m_s[0], cmd.velocity_world_m_s[1]);
        prop_assert!(v_world.is_finite() && cmd.yaw_rad.is_none_or(f32::is_finite));
        prop_assert!(v_world.norm() <= cfg.max_speed_m_s + 1e-4);
        prop_assert!(respects_every_hit(pose.inverse().rotate(v_world), &scan, &cfg));
    }
}
