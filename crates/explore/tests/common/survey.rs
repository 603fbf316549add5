//! Scans of a simulated survey flight, as onboard scans for the SLAM (shared by the online
//! test and the per-scan cost bench, which includes this file by path).

use plumbline_core::scan::{Beam, Scan};
use plumbline_sim::runner::plan::{Plan, PlanLimits};
use plumbline_sim::runner::{run, Pilot, Recorder, SimConfig, Status, TruthPose};
use plumbline_sim::sensors::lidar::{LidarProfile, LidarScan};
use plumbline_sim::world::World;

/// Beams of the XV-11, the lidar these flights use.
pub const BEAMS: usize = 360;

#[derive(Default)]
struct Scans(Vec<LidarScan>);

impl Recorder for Scans {
    fn scan(&mut self, scan: &LidarScan, _: &TruthPose) {
        self.0.push(scan.clone());
    }
}

/// The XV-11 scans of the survey `plumbline sim --world WORLD --scenario survey` flies with
/// `seed`.
pub fn survey_scans(world: &str, seed: u64) -> Vec<Scan<BEAMS>> {
    let world = World::shipped(world).unwrap().unwrap();
    let config = SimConfig::new(world, LidarProfile::xv11(), seed);
    let plan = Plan::survey(&config.world, PlanLimits::default());
    let mut scans = Scans::default();
    let out = run(&config, Pilot::Test(plan), &mut scans).unwrap();
    assert_eq!(out.status, Status::Completed);
    scans.0.iter().map(onboard).collect()
}

fn onboard(s: &LidarScan) -> Scan<BEAMS> {
    let mut scan = Scan::new(s.stamp_s);
    for (k, (&r, &ok)) in s.ranges_m.iter().zip(&s.valid).take(BEAMS).enumerate() {
        let angle = (s.start_angle_rad + s.increment_rad * k as f64) as f32;
        let beam = if ok {
            Beam::new(angle, r)
        } else {
            Beam::invalid(angle)
        };
        scan.push(beam).unwrap();
    }
    scan
}
