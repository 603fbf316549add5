//! The companion's messages as MAVLink 2 datagrams or serial frames: HEARTBEAT as an onboard
//! controller, and ODOMETRY and OBSTACLE_DISTANCE encoded by `plumbline-link` (which owns the
//! frames the autopilots accept and the half turn from Plumbline's ENU/FLU to NED/FRD).

use super::pipeline::AutopilotLink;
use crate::report::CliError;
use plumbline_core::msgs::PoseFix;
use plumbline_core::scan::Beam;
use plumbline_io::link_port::LinkPort;
use plumbline_link::common::{
    MavAutopilot, MavMessage, MavModeFlag, MavState, MavType, HEARTBEAT_DATA,
};
use plumbline_link::{
    obstacle_distance, Link, LinkConfig, LinkTime, ObstacleRange, COMPONENT_ONBOARD_COMPUTER,
};
use std::time::{SystemTime, UNIX_EPOCH};

/// Sends failing with an error (not a full buffer) this many times in a row mean the way to
/// the autopilot is gone (a serial adapter unplugged), and the run ends.
const FAILED_SENDS_LIMIT: u64 = 50;

/// Frames out of one endpoint, each written as it is made.
pub struct MavlinkOut {
    port: LinkPort,
    link: Link,
    /// Nearest return the lidar reports reliably (m): nearer ones are "no data".
    min_range_m: f32,
    frame: Vec<u8>,
    failing_since: Option<u64>,
}

impl MavlinkOut {
    pub fn new(port: LinkPort, system_id: u8, min_range_m: f32) -> Self {
        let link = Link::new(LinkConfig {
            system_id,
            component_id: COMPONENT_ONBOARD_COMPUTER,
            ..LinkConfig::default()
        });
        Self {
            port,
            link,
            min_range_m,
            frame: Vec::with_capacity(300),
            failing_since: None,
        }
    }

    pub fn port(&self) -> &LinkPort {
        &self.port
    }

    /// Frames one message with `encode` and sends it; `Ok(false)` when it was dropped.
    fn send(
        &mut self,
        t_s: f64,
        encode: impl FnOnce(&mut Link, LinkTime, &mut Vec<u8>),
    ) -> Result<bool, CliError> {
        let unix_s = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        self.frame.clear();
        encode(&mut self.link, LinkTime { t_s, unix_s }, &mut self.frame);
        let sent = self.port.send(&self.frame);
        let errors = self.port.counters().send_errors;
        if sent {
            self.failing_since = None;
        } else if errors > 0 {
            let since = *self.failing_since.get_or_insert(errors - 1);
            if errors - since >= FAILED_SENDS_LIMIT {
                return Err(CliError(format!(
                    "MAVLink: the last {FAILED_SENDS_LIMIT} messages could not be sent \
                     (the autopilot's port gone?)"
                )));
            }
        }
        Ok(sent)
    }
}

impl AutopilotLink for MavlinkOut {
    fn heartbeat(&mut self, t_s: f64) -> Result<bool, CliError> {
        let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        });
        self.send(t_s, |link, now, out| link.send(&beat, now, out))
    }

    fn odometry(&mut self, fix: &PoseFix) -> Result<bool, CliError> {
        self.send(fix.t_s, |link, now, out| link.odometry(fix, None, now, out))
    }

    fn obstacles(&mut self, t_s: f64, beams: &[Beam], max_range_m: f32) -> Result<bool, CliError> {
        let range = ObstacleRange {
            min_m: self.min_range_m,
            max_m: max_range_m,
        };
        let message = MavMessage::OBSTACLE_DISTANCE(obstacle_distance(beams, range, t_s));
        self.send(t_s, |link, now, out| link.send(&message, now, out))
    }
}
