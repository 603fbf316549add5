//! The live map on a simulated survey: the SLAM placed scan by scan, the explorer kept
//! current beside it, and at the end its grid is cell for cell the map the slam command draws
//! from the finished back end.

mod common;

use common::survey::{survey_scans, BEAMS};
use plumbline_core::geom::Pose2;
use plumbline_explore::{ExploreConfig, ExploreStep, Explorer};
use plumbline_slam::grid::{Cell, OccupancyGrid};
use plumbline_slam::{local_map_cells, Slam, SlamConfig};

#[test]
fn the_live_map_is_the_final_slam_map() {
    let scans = survey_scans("office", 7);
    // Every accepted loop is optimised at once, so the run ends with nothing pending and the
    // finished back end's poses are the ones the live map last saw.
    let slam_config = SlamConfig {
        optimise_every_keyframes: 1,
        ..SlamConfig::default()
    };
    let mut cells = local_map_cells(&slam_config);
    let mut slam: Slam<BEAMS> = Slam::new(slam_config, &mut cells, false).unwrap();
    let config = ExploreConfig::default();
    let mut explorer = Explorer::new(config).unwrap();
    let mut waypoints = 0;
    let mut last = Pose2::IDENTITY;
    for scan in &scans {
        let at = slam.add_scan(scan, None);
        explorer.observe(&slam, scan, &at).unwrap();
        if let ExploreStep::Waypoint(_) = explorer.next(at.pose) {
            waypoints += 1;
        }
        last = at.pose;
    }
    explorer.map_mut().finish_rebuild(&slam).unwrap();
    let rebuilds = explorer.map().rebuilds();
    let stats = slam.backend_stats();
    println!(
        "{} scans, {} keyframes, {} loops, {} optimisations, {rebuilds} rebuilds, {:?}",
        scans.len(),
        stats.keyframes,
        stats.loops_accepted,
        stats.optimisations,
        explorer.stats()
    );
    assert!(rebuilds >= 1 && rebuilds <= stats.optimisations);
    assert!(waypoints > 0);
    let home = explorer
        .path_home(last)
        .expect("a way home over the mapped floor");
    assert!(home.length_m >= (last.translation() - explorer.home().unwrap()).norm() - 0.1);

    let finished = slam.finish().unwrap();
    let mut reference = OccupancyGrid::new(config.grid).unwrap();
    for (keyframe, &pose) in finished
        .backend
        .keyframes()
        .iter()
        .zip(finished.backend.poses())
    {
        if keyframe.has_scan() {
            reference
                .insert_scan(pose, &keyframe.beams, config.map_range_m)
                .unwrap();
        }
    }
    let live = explorer.map().grid();
    assert_eq!(live.bounds(), reference.bounds());
    let b = reference.bounds().unwrap();
    let mut cells = 0;
    for j in b.min.j..=b.max.j {
        for i in b.min.i..=b.max.i {
            let c = Cell::new(i, j);
            assert_eq!(live.counts(c), reference.counts(c), "cell {c:?}");
            cells += 1;
        }
    }
    assert!(cells > 10_000, "{cells} cells");
}
