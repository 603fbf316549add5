//! The companion's messages as MAVLink 2 datagrams or serial frames: HEARTBEAT as an onboard
//! controller, and ODOMETRY and OBSTACLE_DISTANCE encoded by `plumbline-link` (which owns the
//! frames the autopilots accept and the half turn from Plumbline's ENU/FLU to NED/FRD). The
//! same port brings the autopilot's own estimate back, for the SLAM's motion guess.

use super::pipeline::AutopilotLink;
use crate::report::CliError;
use plumbline_core::msgs::{EstimatedState, PoseFix};
use plumbline_core::scan::Beam;
use plumbline_io::link_port::LinkPort;
use plumbline_link::common::{
    MavAutopilot, MavMessage, MavModeFlag, MavState, MavType, HEARTBEAT_DATA,
};
use plumbline_link::{
    obstacle_distance, EstimateWatch, InboundEvent, Link, LinkConfig, LinkTime, ObstacleRange,
    Withheld, COMPONENT_ONBOARD_COMPUTER,
};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// Sends failing with an error (not a full buffer) this many times in a row mean the way to
/// the autopilot is gone (a serial adapter unplugged), and the run ends.
const FAILED_SENDS_LIMIT: u64 = 50;

/// Reads per revolution at most: what is left waits for the next, so a flood on the port cannot
/// stall the SLAM.
const MAX_READS_PER_REVOLUTION: usize = 512;

/// Frames out of one endpoint, each written as it is made, and the autopilot's estimate in.
pub struct MavlinkOut {
    port: LinkPort,
    link: Link,
    /// Nearest return the lidar reports reliably (m): nearer ones are "no data".
    min_range_m: f32,
    frame: Vec<u8>,
    failing_since: Option<u64>,
    watch: EstimateWatch,
    /// The clock samples are timed on (monotonic: the host's clock may be stepped).
    started: Instant,
    rx: Vec<u8>,
    events: Vec<InboundEvent>,
}

impl MavlinkOut {
    /// `estimate_timeout_s`: the autopilot's estimate older than this guesses nothing.
    pub fn new(port: LinkPort, system_id: u8, min_range_m: f32, estimate_timeout_s: f64) -> Self {
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
            watch: EstimateWatch::new(estimate_timeout_s),
            started: Instant::now(),
            rx: vec![0; 4096],
            events: Vec::new(),
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

    /// Reads what the autopilot sent since the last call and judges its estimate now. Anything
    /// else that arrives (a ground station's command for this component) is not acted on: the
    /// link answers what it cannot carry out, and those answers are not sent.
    fn estimate(&mut self) -> Result<EstimatedState, Withheld> {
        let mut replies = Vec::new();
        for _ in 0..MAX_READS_PER_REVOLUTION {
            let Some(bytes) = self.port.receive(&mut self.rx) else {
                break;
            };
            let now_s = self.started.elapsed().as_secs_f64();
            // Unix time only checks signatures, and this link has no key.
            let now = LinkTime {
                t_s: now_s,
                unix_s: 0.0,
            };
            self.link
                .receive(bytes, now, &mut self.events, &mut replies);
            for event in self.events.drain(..) {
                if let InboundEvent::Estimate(sample) = event {
                    self.watch.take(&sample, now_s);
                }
            }
        }
        self.watch.reading(self.started.elapsed().as_secs_f64())
    }
}
