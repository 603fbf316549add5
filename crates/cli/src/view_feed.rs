//! What the commands with a web view hand it: a scan map built from the pose and each
//! revolution, and a snapshot at the view's frame rate. Shared by the simulator's view station
//! and the companion computer, which differ only in where pose and scans come from.

use plumbline_core::msgs::{FailsafeReason, FlightMode};
use plumbline_core::scan::Beam;
use plumbline_view::{scan_points, OccupancyImage, ScanMap, Snapshot, View, MAX_FRAME_HZ};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often the map image is copied for the view, wall-clock time: the view sends maps no
/// faster, and a run faster than real time would otherwise copy it hundreds of times a second.
const MAP_PERIOD: Duration = Duration::from_millis(500);

/// The state of one instant besides the pose: what the page shows in its panel.
pub struct Status {
    pub battery_v: Option<f32>,
    /// `None` where the mode is not known (a companion beside another autopilot).
    pub mode: Option<FlightMode>,
    pub failsafe: Option<FailsafeReason>,
}

pub struct ViewFeed {
    map: ScanMap,
    map_image: Option<Arc<OccupancyImage>>,
    scan_m: Vec<[f32; 2]>,
    next_frame_s: f64,
    map_at: Option<Instant>,
}

impl ViewFeed {
    /// A feed whose map covers the square of half side `half_side_m` around the origin.
    pub fn new(half_side_m: f64) -> Self {
        Self {
            map: ScanMap::new([0.0, 0.0], half_side_m),
            map_image: None,
            scan_m: Vec::new(),
            next_frame_s: 0.0,
            map_at: None,
        }
    }

    /// Takes one instant: `pose` is x, y, z (m) and yaw (rad) in the map frame; a revolution
    /// completed now is laid into the map when the pose is `valid`. Publishes a snapshot when
    /// the view's frame period (in the run's own time `t_s`) has passed.
    pub fn update(
        &mut self,
        view: &View,
        t_s: f64,
        pose: [f64; 4],
        valid: bool,
        beams: Option<&[Beam]>,
        status: Status,
    ) {
        let planar = [pose[0], pose[1], pose[3]];
        if let Some(beams) = beams {
            scan_points(planar, beams, &mut self.scan_m);
            if valid {
                self.map.add(planar, beams);
            }
        }
        if t_s < self.next_frame_s {
            return;
        }
        self.next_frame_s = t_s + 1.0 / MAX_FRAME_HZ;
        if self.map_at.is_none_or(|t| t.elapsed() >= MAP_PERIOD) {
            self.map_at = Some(Instant::now());
            self.map_image = Some(self.map.image());
        }
        view.publish(Snapshot {
            t_s,
            pose,
            estimate_valid: valid,
            scan_m: self.scan_m.clone(),
            battery_v: status.battery_v,
            mode: status.mode,
            failsafe: status.failsafe,
            map: self.map_image.clone(),
        });
    }
}
