//! What exploration costs per scan, beside the SLAM it rides on: the survey flights of
//! `office` and `building` with the XV-11, the SLAM's back end inline (as a lockstep simulation
//! runs it), the live map updated and the next waypoint asked for after every scan. Prints
//! one JSON line per world with the median, p99 and maximum of each part in microseconds.
//! At 500x real time a 5 Hz lidar leaves 400 us per scan for everything.
//!
//! `cargo bench -p plumbline-explore --bench per_scan`

#[path = "../tests/common/survey.rs"]
mod survey;

use plumbline_explore::{ExploreConfig, Explorer};
use plumbline_slam::{local_map_cells, Slam, SlamConfig};
use std::time::Instant;
use survey::{survey_scans, BEAMS};

/// Median, p99 and maximum of `v`, us.
fn figures(mut v: Vec<f64>) -> String {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    format!(
        "{{\"median_us\": {:.1}, \"p99_us\": {:.1}, \"max_us\": {:.1}, \"mean_us\": {:.1}}}",
        at(0.5),
        at(0.99),
        at(1.0),
        v.iter().sum::<f64>() / v.len() as f64
    )
}

fn main() {
    for world in ["office", "building"] {
        let scans = survey_scans(world, 7);
        let config = SlamConfig::default();
        let mut cells = local_map_cells(&config);
        let mut slam: Slam<BEAMS> = Slam::new(config, &mut cells, false).unwrap();
        let mut explorer = Explorer::new(ExploreConfig::default()).unwrap();
        let (mut slam_us, mut map_us, mut next_us, mut explore_us) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let us = |t: Instant| t.elapsed().as_secs_f64() * 1e6;
        for scan in &scans {
            let t = Instant::now();
            let at = slam.add_scan(scan, None);
            slam_us.push(us(t));
            let t = Instant::now();
            explorer.observe(&slam, scan, &at).unwrap();
            let map = us(t);
            let t = Instant::now();
            std::hint::black_box(explorer.next(at.pose));
            let next = us(t);
            map_us.push(map);
            next_us.push(next);
            explore_us.push(map + next);
        }
        let t = Instant::now();
        let home = std::hint::black_box(
            explorer.path_home(
                scans
                    .last()
                    .map_or(plumbline_core::geom::Pose2::IDENTITY, |_| {
                        slam.keyframe_pose(slam.keyframe_count() - 1).unwrap()
                    }),
            ),
        );
        let home_us = us(t);
        let stats = explorer.stats();
        println!(
            "{{\"world\": \"{world}\", \"lidar\": \"xv11\", \"scans\": {}, \"keyframes\": {}, \
             \"map_rebuilds\": {}, \"plans\": {}, \"full_map_plans\": {}, \"known_free_m2\": {:.1}, \
             \"slam\": {}, \"map_update\": {}, \"next\": {}, \"explore_total\": {}, \
             \"path_home_us\": {home_us:.1}, \"path_home_m\": {:.2}}}",
            scans.len(),
            slam.keyframe_count(),
            stats.map_rebuilds,
            stats.plans,
            stats.full_map_plans,
            stats.known_free_m2,
            figures(slam_us),
            figures(map_us),
            figures(next_us),
            figures(explore_us),
            home.map_or(f32::NAN, |p| p.length_m),
        );
    }
}
