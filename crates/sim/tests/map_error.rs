//! The map-error metric on real simulated surveys: scans inserted into the occupancy grid at
//! their true poses give the smallest error SLAM can reach with this grid (the floor, printed
//! per world and lidar), and maps built or placed with a known pose error score worse.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::Beam;
use plumbline_sim::map_error::{grid_map_error, MapError};
use plumbline_sim::runner::plan::{Plan, PlanLimits};
use plumbline_sim::runner::{run, Pilot, Recorder, SimConfig, Status, TruthPose};
use plumbline_sim::sensors::lidar::{LidarProfile, LidarScan};
use plumbline_sim::world::World;
use plumbline_slam::grid::{GridConfig, OccupancyGrid, PreparedScan};

#[derive(Default)]
struct Scans(Vec<(LidarScan, TruthPose)>);

impl Recorder for Scans {
    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        self.0.push((scan.clone(), *truth));
    }
}

/// The survey of `world` with `lidar`, seed 7 (what `plumbline sim --scenario survey` flies).
fn survey(world: &str, lidar: LidarProfile) -> (World, Vec<(LidarScan, TruthPose)>) {
    let config = SimConfig::new(World::shipped(world).unwrap().unwrap(), lidar, 7);
    let plan = Plan::survey(&config.world, PlanLimits::default());
    let mut scans = Scans::default();
    let out = run(&config, Pilot::Test(plan), &mut scans).unwrap();
    assert_eq!(out.status, Status::Completed);
    (config.world, scans.0)
}

/// Planar pose (x, y, yaw) of a truth sample.
fn planar(t: &TruthPose) -> [f64; 3] {
    [t.position.x, t.position.y, t.attitude.yaw()]
}

/// `inverse(a) * b` for planar poses.
fn between(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    [c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]]
}

fn apply(a: [f64; 3], p: [f64; 2]) -> [f64; 2] {
    let (s, c) = a[2].sin_cos();
    [c * p[0] - s * p[1] + a[0], s * p[0] + c * p[1] + a[1]]
}

fn pose2(p: [f64; 3]) -> Pose2 {
    Pose2::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

/// The true planar pose at `t_s`, interpolated between two scan truths.
fn interpolate(a: &TruthPose, b: &TruthPose, t_s: f64) -> [f64; 3] {
    let (pa, pb) = (planar(a), planar(b));
    let u = ((t_s - a.t_s) / (b.t_s - a.t_s)).clamp(0.0, 1.0);
    let dyaw = plumbline_core::geom::normalize_angle_f64(pb[2] - pa[2]);
    [
        pa[0] + u * (pb[0] - pa[0]),
        pa[1] + u * (pb[1] - pa[1]),
        pa[2] + u * dyaw,
    ]
}

/// A grid of every scan at its true pose in the map frame (the first scan's pose), each moved
/// by `nudge(k)` (m, in the map frame). With `deskew`, each beam is placed from the true pose
/// at its own instant, as a front end that removes the sweep's motion would; without, the
/// whole revolution is placed at the pose of its first beam.
fn true_pose_grid(
    scans: &[(LidarScan, TruthPose)],
    config: GridConfig,
    deskew: bool,
    nudge: impl Fn(usize) -> [f64; 2],
) -> OccupancyGrid {
    let mut grid = OccupancyGrid::new(config).unwrap();
    let origin = planar(&scans[0].1);
    for (k, (scan, truth)) in scans.iter().enumerate() {
        let at = planar(truth);
        let mut pose = between(origin, at);
        let [nx, ny] = nudge(k);
        (pose[0], pose[1]) = (pose[0] + nx, pose[1] + ny);
        let angle = |b: usize| scan.start_angle_rad + b as f64 * scan.increment_rad;
        let next = scans.get(k + 1).map(|(_, t)| t);
        let prepared = match next.filter(|_| deskew) {
            Some(next) => {
                let mut p = PreparedScan::new();
                for (b, (&r, &ok)) in scan.ranges_m.iter().zip(&scan.valid).enumerate() {
                    if ok {
                        let beam_pose =
                            interpolate(truth, next, scan.stamp_s + b as f64 * scan.beam_dt_s);
                        let (s, c) = angle(b).sin_cos();
                        let world = apply(beam_pose, [f64::from(r) * c, f64::from(r) * s]);
                        let q = between(at, [world[0], world[1], 0.0]);
                        p.push_hit(Vec2::new(q[0] as f32, q[1] as f32));
                    }
                }
                p
            }
            None => {
                let beams: Vec<Beam> = scan
                    .ranges_m
                    .iter()
                    .zip(&scan.valid)
                    .enumerate()
                    .map(|(b, (&r, &ok))| Beam {
                        valid: ok,
                        ..Beam::new(angle(b) as f32, r)
                    })
                    .collect();
                PreparedScan::from_beams(&beams, scan.max_range_m as f32, None).unwrap()
            }
        };
        grid.insert(pose2(pose), &prepared).unwrap();
    }
    grid
}

fn no_nudge(_: usize) -> [f64; 2] {
    [0.0, 0.0]
}

fn score(world: &World, scans: &[(LidarScan, TruthPose)], grid: &OccupancyGrid) -> MapError {
    grid_map_error(grid, world, planar(&scans[0].1)).unwrap()
}

/// The floor for one world and lidar, with the world's walking people as `plumbline sim`
/// flies them: printed, and the de-skewed one held to the SLAM target.
fn floor(world: &str, lidar: LidarProfile, target_m: f64) {
    let name = lidar.name;
    let (w, scans) = survey(world, lidar);
    let skewed = score(
        &w,
        &scans,
        &true_pose_grid(&scans, GridConfig::default(), false, no_nudge),
    );
    let deskewed = score(
        &w,
        &scans,
        &true_pose_grid(&scans, GridConfig::default(), true, no_nudge),
    );
    for (how, e) in [("scan pose", skewed), ("de-skewed", deskewed)] {
        println!(
            "map error floor {world} {name} {how}: mean {:.4} m, p95 {:.4} m, {:.2} % beyond two \
             cells, {} occupied cells, {} scans",
            e.mean_m,
            e.p95_m,
            100.0 * e.far_fraction,
            e.occupied_cells,
            scans.len()
        );
    }
    assert!(deskewed.mean_m <= target_m, "{world} {name}: {deskewed:?}");
    assert!(
        deskewed.occupied_cells > 1000,
        "{world} {name}: {deskewed:?}"
    );
}

#[test]
fn floor_office_xv11() {
    floor("office", LidarProfile::xv11(), 0.08);
}

#[test]
fn floor_office_urg04lx() {
    floor("office", LidarProfile::urg04lx(), 0.08);
}

#[test]
fn floor_office_utm30lx() {
    floor("office", LidarProfile::utm30lx(), 0.05);
}

#[test]
fn floor_building_xv11() {
    floor("building", LidarProfile::xv11(), 0.08);
}

#[test]
fn floor_building_urg04lx() {
    floor("building", LidarProfile::urg04lx(), 0.08);
}

#[test]
fn floor_building_utm30lx() {
    floor("building", LidarProfile::utm30lx(), 0.05);
}

/// A map placed 0.2 m off, or built from scans that alternate 0.15 m apart, scores worse than
/// the true-pose map by about what the geometry says.
#[test]
fn pose_errors_raise_the_map_error() {
    let (w, scans) = survey("office", LidarProfile::utm30lx());
    let grid = true_pose_grid(&scans, GridConfig::default(), true, no_nudge);
    let truth = score(&w, &scans, &grid);
    let start = planar(&scans[0].1);
    let shifted = grid_map_error(&grid, &w, [start[0] + 0.2, start[1], start[2]]).unwrap();
    println!("true {truth:?}\nshifted 0.2 m {shifted:?}");
    // The cells of walls across x move 0.2 m off (from half a cell to 4.5 cells away: all of
    // them beyond two cells), those along x slide along their wall and stay where they were.
    assert!(shifted.mean_m > truth.mean_m + 0.05, "{shifted:?}");
    let expected = truth.mean_m + shifted.far_fraction * (0.2 - truth.mean_m);
    assert!(
        (shifted.mean_m - expected).abs() < 0.01,
        "{shifted:?}, expected {expected}"
    );
    assert!(shifted.far_fraction > 0.25, "{shifted:?}");
    let split = score(
        &w,
        &scans,
        &true_pose_grid(&scans, GridConfig::default(), true, |k| {
            [0.0, if k % 2 == 0 { 0.15 } else { 0.0 }]
        }),
    );
    println!("alternate scans 0.15 m apart {split:?}");
    // Walls across y are seen twice, 3 cells apart: about half their cells are off by 0.15 m.
    assert!(split.mean_m > truth.mean_m + 0.025, "{split:?}");
    assert!(split.far_fraction > 0.15, "{split:?}");
}
