//! The live web view as the simulator's ground station: after each onboard step it takes what
//! the vehicle reports, publishes a snapshot at the view's frame rate (simulated time) and
//! hands the page's accepted commands to the autopilot.
//!
//! The map shown is built from the onboard estimate and the scans (see
//! `plumbline_view::ScanMap`), not from the world: the page shows what the vehicle believes,
//! in its estimate frame (origin and heading at power-up).

use crate::view_feed::{Status, ViewFeed};
use plumbline_core::msgs::GroundMessages;
use plumbline_sim::runner::ground::{GroundStation, Parameters, VehicleReport};
use plumbline_sim::world::World;
use plumbline_view::View;
use std::rc::Rc;

/// Room around the world's walls in the map, m.
const MAP_MARGIN_M: f64 = 2.0;

pub struct ViewStation {
    view: Rc<View>,
    feed: ViewFeed,
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
            feed: ViewFeed::new(reach + MAP_MARGIN_M),
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
        let [x, y, z] = e.position_m.map(f64::from);
        let status = Status {
            battery_v: Some(report.battery.voltage_v),
            mode: Some(report.outputs.mode),
            failsafe: report.outputs.failsafe,
        };
        let pose = [x, y, z, f64::from(e.yaw_rad)];
        self.feed
            .update(&self.view, report.t_s, pose, e.valid, report.scan, status);
        // The view is no radio link: it sends no heartbeat, so closing the page never raises
        // the link-lost failsafe.
        GroundMessages {
            command: self.view.try_command(),
            heartbeat: false,
        }
    }
}
