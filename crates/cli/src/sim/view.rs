//! The live web view as the simulator's ground station: after each onboard step it takes what
//! the vehicle reports, publishes a snapshot at the view's frame rate (simulated time) and
//! hands the page's accepted commands to the autopilot.
//!
//! The map shown is built from the onboard estimate and the scans (see
//! `plumbline_view::ScanMap`), not from the world: the page shows what the vehicle believes,
//! in its estimate frame (origin and heading at power-up).

use plumbline_core::msgs::GroundMessages;
use plumbline_sim::runner::ground::{GroundStation, Parameters, VehicleReport};
use plumbline_sim::world::World;
use plumbline_view::{scan_points, OccupancyImage, ScanMap, Snapshot, View, MAX_FRAME_HZ};
use std::rc::Rc;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often the map image is copied for the view, wall-clock time: the view sends maps no
/// faster, and a run faster than real time would otherwise copy it hundreds of times a second.
const MAP_PERIOD: Duration = Duration::from_millis(500);
/// Room around the world's walls in the map, m.
const MAP_MARGIN_M: f64 = 2.0;

pub struct ViewStation {
    view: Rc<View>,
    map: ScanMap,
    map_image: Option<Arc<OccupancyImage>>,
    scan_m: Vec<[f32; 2]>,
    next_frame_s: f64,
    map_at: Option<Instant>,
}

impl ViewStation {
    /// A station whose map covers `world` seen from its take-off point, whatever the heading.
    pub fn new(view: Rc<View>, world: &World) -> Self {
        let [x0, y0, x1, y1] = world.bounds();
        let [sx, sy, _] = world.start;
        let reach = [[x0, y0], [x0, y1], [x1, y0], [x1, y1]]
            .iter()
            .map(|c| (c[0] - sx).hypot(c[1] - sy))
            .fold(0.0, f64::max);
        Self {
            view,
            map: ScanMap::new([0.0, 0.0], reach + MAP_MARGIN_M),
            map_image: None,
            scan_m: Vec::new(),
            next_frame_s: 0.0,
            map_at: None,
        }
    }
}

impl GroundStation for ViewStation {
    fn exchange(
        &mut self,
        report: &VehicleReport<'_>,
        _parameters: &mut Parameters<'_>,
    ) -> GroundMessages {
        let e = &report.outputs.estimate;
        let pose = [e.position_m[0], e.position_m[1], e.yaw_rad].map(f64::from);
        if let Some(beams) = report.scan {
            scan_points(pose, beams, &mut self.scan_m);
            if e.valid {
                self.map.add(pose, beams);
            }
        }
        if report.t_s >= self.next_frame_s {
            self.next_frame_s = report.t_s + 1.0 / MAX_FRAME_HZ;
            if self.map_at.is_none_or(|t| t.elapsed() >= MAP_PERIOD) {
                self.map_at = Some(Instant::now());
                self.map_image = Some(self.map.image());
            }
            self.view.publish(Snapshot {
                t_s: report.t_s,
                pose: [pose[0], pose[1], f64::from(e.position_m[2]), pose[2]],
                estimate_valid: e.valid,
                scan_m: self.scan_m.clone(),
                battery_v: Some(report.battery.voltage_v),
                mode: report.outputs.mode,
                failsafe: report.outputs.failsafe,
                map: self.map_image.clone(),
            });
        }
        // The view is no radio link: it sends no heartbeat, so closing the page never raises
        // the link-lost failsafe.
        GroundMessages {
            command: self.view.try_command(),
            heartbeat: false,
        }
    }
}
