//! The companion's messages as MAVLink 2 frames on an endpoint: HEARTBEAT, ODOMETRY and
//! OBSTACLE_DISTANCE, in the frames the autopilots accept (pose in LOCAL_FRD, body in
//! BODY_FRD, estimator VISION: ArduPilot ignores other frame pairs, PX4 rejects LIDAR).
//!
//! Plumbline's map frame is x forward at start, y left (ENU-like) and its body FLU; the wire
//! uses the half turn about x (y and z negated, headings clockwise), so "north" is the heading
//! the vehicle had when the SLAM started and the autopilot anchors that frame to its own.

use super::pipeline::AutopilotLink;
use crate::report::CliError;
use mavlink::dialects::common::{
    MavAutopilot, MavDistanceSensor, MavEstimatorType, MavFrame, MavMessage, MavModeFlag,
    MavState, MavType, HEARTBEAT_DATA, OBSTACLE_DISTANCE_DATA, ODOMETRY_DATA,
};
use mavlink::MavHeader;
use plumbline_core::msgs::PoseFix;
use plumbline_core::scan::sectors::{ObstacleSectors, SECTOR_COUNT};
use plumbline_io::link_port::LinkPort;

/// MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY: the component a pose source speaks as.
const COMPONENT_ID: u8 = 197;
/// Variance sent for what a 2-D lidar does not measure: height, roll and pitch (m², rad²).
/// The autopilots take those from their own sensors; this says the fix has nothing to add.
const UNMEASURED_VARIANCE: f32 = 100.0;
/// OBSTACLE_DISTANCE's "no obstacle in range" is max_distance + 1; "unknown" is u16::MAX.
const UNKNOWN_CM: u16 = u16::MAX;
/// Nearest distance the sectors claim (cm): below it the autopilot ignores a reading.
const MIN_DISTANCE_CM: u16 = 2;

/// Sends failing with an error (not a full buffer) this many times in a row mean the way to
/// the autopilot is gone (a serial adapter unplugged), and the run ends.
const FAILED_SENDS_LIMIT: u64 = 50;

/// Frames out of one endpoint, numbered in sequence.
pub struct MavlinkOut {
    port: LinkPort,
    system_id: u8,
    sequence: u8,
    frame: Vec<u8>,
    failing_since: Option<u64>,
}

impl MavlinkOut {
    pub fn new(port: LinkPort, system_id: u8) -> Self {
        Self {
            port,
            system_id,
            sequence: 0,
            frame: Vec::with_capacity(300),
            failing_since: None,
        }
    }

    pub fn port(&self) -> &LinkPort {
        &self.port
    }

    fn send(&mut self, message: &MavMessage) -> Result<bool, CliError> {
        let header = MavHeader {
            system_id: u32::from(self.system_id),
            component_id: COMPONENT_ID,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.frame.clear();
        mavlink::write_v2_msg(&mut self.frame, header, message)
            .map_err(|e| CliError(format!("MAVLink: cannot encode a frame: {e}")))?;
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

fn time_usec(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e6) as u64
}

/// ODOMETRY for a pose fix, in the wire's frames.
pub fn odometry(fix: &PoseFix) -> ODOMETRY_DATA {
    let yaw_frd = -fix.yaw_rad;
    let (s, c) = (0.5 * yaw_frd).sin_cos();
    // (x, y, yaw) of the fix at rows 0, 1, 5 of the 6x6 (x y z roll pitch yaw); y and yaw
    // change sign on the wire, so their products with x change sign and with each other not.
    let sign = [1.0, -1.0, -1.0];
    let at = [0usize, 1, 5];
    let mut full = [[0.0f32; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            full[at[i]][at[j]] = fix.covariance[i][j] * sign[i] * sign[j];
        }
    }
    for k in [2, 3, 4] {
        full[k][k] = UNMEASURED_VARIANCE;
    }
    let mut pose_covariance = [0.0f32; 21];
    let mut k = 0;
    for (i, row) in full.iter().enumerate() {
        for v in &row[i..] {
            pose_covariance[k] = *v;
            k += 1;
        }
    }
    let mut velocity_covariance = [0.0f32; 21];
    velocity_covariance[0] = f32::NAN;
    ODOMETRY_DATA {
        time_usec: time_usec(fix.t_s),
        x: fix.position_m[0],
        y: -fix.position_m[1],
        z: 0.0,
        q: [c, 0.0, 0.0, s],
        vx: f32::NAN,
        vy: f32::NAN,
        vz: f32::NAN,
        rollspeed: f32::NAN,
        pitchspeed: f32::NAN,
        yawspeed: f32::NAN,
        pose_covariance,
        velocity_covariance,
        frame_id: MavFrame::MAV_FRAME_LOCAL_FRD,
        child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
        reset_counter: fix.reset_counter,
        estimator_type: MavEstimatorType::MAV_ESTIMATOR_TYPE_VISION,
        quality: fix.quality_pct.map_or(-1, |q| q.min(100) as i8),
    }
}

/// OBSTACLE_DISTANCE for a revolution: sector `j` of the message is `j` sectors clockwise
/// from ahead (body FRD), which is Plumbline's sector `-j`.
pub fn obstacles(sectors: &ObstacleSectors, max_range_m: f32) -> OBSTACLE_DISTANCE_DATA {
    let max_cm = (max_range_m * 100.0).clamp(f32::from(MIN_DISTANCE_CM) + 1.0, 65_000.0) as u16;
    let distances = core::array::from_fn(|j| {
        match sectors.nearest_m[(SECTOR_COUNT - j) % SECTOR_COUNT] {
            None => UNKNOWN_CM,
            Some(r) => ((r * 100.0).round() as u16).clamp(MIN_DISTANCE_CM, max_cm),
        }
    });
    let width_deg = 360.0 / SECTOR_COUNT as f32;
    OBSTACLE_DISTANCE_DATA {
        time_usec: time_usec(sectors.t_s),
        distances,
        min_distance: MIN_DISTANCE_CM,
        max_distance: max_cm,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment: width_deg.round() as u8,
        increment_f: width_deg,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_BODY_FRD,
    }
}

impl AutopilotLink for MavlinkOut {
    fn heartbeat(&mut self, _t_s: f64) -> Result<bool, CliError> {
        self.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }))
    }

    fn odometry(&mut self, fix: &PoseFix) -> Result<bool, CliError> {
        self.send(&MavMessage::ODOMETRY(odometry(fix)))
    }

    fn obstacles(
        &mut self,
        sectors: &ObstacleSectors,
        max_range_m: f32,
    ) -> Result<bool, CliError> {
        self.send(&MavMessage::OBSTACLE_DISTANCE(obstacles(sectors, max_range_m)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_2;

    #[test]
    fn a_pose_to_the_left_facing_left_is_west_facing_west_on_the_wire() {
        let fix = PoseFix {
            t_s: 2.5,
            position_m: [1.0, 2.0],
            yaw_rad: FRAC_PI_2,
            covariance: [[0.01, 0.002, 0.003], [0.002, 0.04, 0.0], [0.003, 0.0, 0.001]],
            quality_pct: Some(87),
            reset_counter: 4,
        };
        let o = odometry(&fix);
        assert_eq!((o.time_usec, o.x, o.y, o.z), (2_500_000, 1.0, -2.0, 0.0));
        // Heading -90 degrees about z down: w = cos(-45), z = sin(-45).
        let h = core::f32::consts::FRAC_1_SQRT_2;
        assert!((o.q[0] - h).abs() < 1e-6 && (o.q[3] + h).abs() < 1e-6, "{:?}", o.q);
        let c = o.pose_covariance;
        // Rows x (0..6), y (6..11), z (11..15), roll (15..18), pitch (18..20), yaw (20).
        assert_eq!((c[0], c[1], c[5]), (0.01, -0.002, -0.003));
        assert_eq!((c[6], c[10], c[20]), (0.04, 0.0, 0.001));
        assert_eq!((c[11], c[15], c[18]), (100.0, 100.0, 100.0));
        assert_eq!((o.quality, o.reset_counter), (87, 4));
        let lost = odometry(&PoseFix {
            quality_pct: None,
            ..fix
        });
        assert_eq!(lost.quality, -1);
    }

    #[test]
    fn obstacle_sectors_turn_clockwise_and_unknown_stays_unknown() {
        let mut nearest_m = [None; SECTOR_COUNT];
        nearest_m[0] = Some(1.234);
        nearest_m[18] = Some(0.5); // on the left: 270 degrees clockwise
        nearest_m[54] = Some(30.0); // on the right, beyond the lidar's reach
        let o = obstacles(&ObstacleSectors { t_s: 1.0, nearest_m }, 6.0);
        assert_eq!((o.distances[0], o.distances[54], o.distances[18]), (123, 50, 600));
        assert_eq!((o.min_distance, o.max_distance), (MIN_DISTANCE_CM, 600));
        assert_eq!(o.distances.iter().filter(|d| **d == UNKNOWN_CM).count(), 69);
        assert_eq!((o.increment, o.increment_f), (5, 5.0));
    }
}
