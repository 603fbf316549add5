//! Vehicle to ground: which messages go out at which rate, built from core's plain values.
//!
//! Default rates (configurable, 0 turns a stream off):
//!
//! | message            | Hz  | content                                                  |
//! |--------------------|-----|----------------------------------------------------------|
//! | HEARTBEAT          | 1   | mode, armed, status ([`crate::modes`])                   |
//! | SYS_STATUS         | 1   | sensors present/healthy, battery voltage                 |
//! | BATTERY_STATUS     | 1   | cell-pack voltage, charge state from the failsafes       |
//! | ATTITUDE           | 50  | roll, pitch, yaw and body rates (NED/FRD)                |
//! | LOCAL_POSITION_NED | 50  | position and velocity (NED)                              |
//! | ODOMETRY           | 10  | the estimate with its position variances                 |
//! | DISTANCE_SENSOR    | 10  | the sonar, pointing down (when a sample exists)          |
//! | OBSTACLE_DISTANCE  | 10  | 72 sectors of the latest scan (when a scan exists)       |
//! | STATUSTEXT         | -   | on every mode change and every new failsafe              |
//!
//! A stream is due when the caller's clock reaches its next slot; slots advance by whole
//! periods, so a 50 Hz stream sent from a 200 Hz loop goes out exactly every fourth step and
//! a late step does not make a burst.

use crate::modes::{base_mode, custom_mode, system_status};
use crate::ned::{flip_euler, flip_yz};
use crate::obstacle::{obstacle_distance, ObstacleRange};
use crate::odometry::odometry_from_estimate;
use mavlink::dialects::common::{
    MavAutopilot, MavBatteryChargeState, MavBatteryFault, MavBatteryFunction, MavBatteryMode,
    MavBatteryType, MavDistanceSensor, MavMessage, MavSensorOrientation, MavSeverity,
    MavSysStatusSensor, MavSysStatusSensorExtended, MavType, ATTITUDE_DATA, BATTERY_STATUS_DATA,
    DISTANCE_SENSOR_DATA, HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA, STATUSTEXT_DATA,
    SYS_STATUS_DATA,
};
use plumbline_core::msgs::{BatterySample, FailsafeReason, FlightMode, Outputs, SonarSample};
use plumbline_core::scan::Beam;

/// MAVLink's protocol version byte in HEARTBEAT.
const MAVLINK_VERSION: u8 = 3;

/// Everything the telemetry is built from, as the vehicle has it after one step.
#[derive(Clone, Copy, Debug)]
pub struct TelemetryInput<'a> {
    /// What the autopilot returned this step (mode, failsafe, estimate).
    pub outputs: &'a Outputs,
    /// Body rates (FLU, rad/s), the gyro's reading.
    pub body_rates_rad_s: [f32; 3],
    /// The latest battery reading, if any so far.
    pub battery: Option<BatterySample>,
    /// The latest sonar reading, if any so far.
    pub sonar: Option<SonarSample>,
    /// The latest complete lidar revolution, if any so far.
    pub scan: Option<&'a [Beam]>,
}

/// Rates of the periodic messages (Hz; 0 = off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TelemetryRates {
    pub heartbeat_hz: f64,
    pub sys_status_hz: f64,
    pub battery_status_hz: f64,
    pub attitude_hz: f64,
    pub local_position_hz: f64,
    pub odometry_hz: f64,
    pub distance_sensor_hz: f64,
    pub obstacle_distance_hz: f64,
}

impl Default for TelemetryRates {
    fn default() -> Self {
        Self {
            heartbeat_hz: 1.0,
            sys_status_hz: 1.0,
            battery_status_hz: 1.0,
            attitude_hz: 50.0,
            local_position_hz: 50.0,
            odometry_hz: 10.0,
            distance_sensor_hz: 10.0,
            obstacle_distance_hz: 10.0,
        }
    }
}

/// The sensors' ranges as DISTANCE_SENSOR and OBSTACLE_DISTANCE report them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorRanges {
    /// The downward sonar's usable range (m).
    pub sonar_min_m: f32,
    pub sonar_max_m: f32,
    pub lidar: ObstacleRange,
}

impl Default for SensorRanges {
    /// A common hobby ultrasonic ranger (0.2 to 4 m) and the XV-11.
    fn default() -> Self {
        Self {
            sonar_min_m: 0.2,
            sonar_max_m: 4.0,
            lidar: ObstacleRange::default(),
        }
    }
}

/// Tolerance on a slot time, so a clock that adds `dt` repeatedly in f64 is not a step late.
const SLOT_TOLERANCE_S: f64 = 1e-9;

#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    next_s: Option<f64>,
}

impl Slot {
    /// True when a message at `hz` is due at `t_s`; then books the next slot.
    fn due(&mut self, hz: f64, t_s: f64) -> bool {
        if hz.is_nan() || hz <= 0.0 || !t_s.is_finite() {
            return false;
        }
        let period = 1.0 / hz;
        match self.next_s {
            Some(next) if t_s + SLOT_TOLERANCE_S < next => false,
            Some(next) => {
                // Behind by more than a period (a stall, a clock jump): start afresh, no burst.
                let after = next + period;
                self.next_s = Some(if after + SLOT_TOLERANCE_S < t_s {
                    t_s + period
                } else {
                    after
                });
                true
            }
            None => {
                self.next_s = Some(t_s + period);
                true
            }
        }
    }
}

/// Schedules the periodic messages and notices mode and failsafe changes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Telemetry {
    rates: TelemetryRates,
    ranges: SensorRanges,
    slots: [Slot; 8],
    last_mode: Option<FlightMode>,
    last_failsafe: Option<FailsafeReason>,
}

/// Microseconds for MAVLink's `time_usec` fields (time since the caller's clock started).
pub(crate) fn usec(t_s: f64) -> u64 {
    if t_s.is_finite() && t_s > 0.0 {
        (t_s * 1e6) as u64
    } else {
        0
    }
}

/// Milliseconds for `time_boot_ms` (wraps after 49 days, as the field does).
fn boot_ms(t_s: f64) -> u32 {
    (usec(t_s) / 1000) as u32
}

/// A voltage in millivolts, saturating; UINT16_MAX is MAVLink's "unknown".
fn millivolts(v: f32) -> u16 {
    if v.is_finite() && v >= 0.0 {
        (v * 1000.0).round().min(f32::from(u16::MAX - 1)) as u16
    } else {
        u16::MAX
    }
}

impl Telemetry {
    pub(crate) fn new(rates: TelemetryRates, ranges: SensorRanges) -> Self {
        Self {
            rates,
            ranges,
            ..Self::default()
        }
    }

    pub(crate) fn ranges(&self) -> SensorRanges {
        self.ranges
    }

    /// Builds every message due at `t` and hands each to `send`, status texts first.
    pub(crate) fn step(
        &mut self,
        report: &TelemetryInput<'_>,
        t: f64,
        mut send: impl FnMut(&MavMessage),
    ) {
        let out = report.outputs;
        if self.last_mode != Some(out.mode) {
            // The first report announces the starting mode too: a ground station that joins
            // sees where the vehicle is.
            send(&statustext(
                MavSeverity::MAV_SEVERITY_NOTICE,
                &format!("mode {}", out.mode.name()),
            ));
            self.last_mode = Some(out.mode);
        }
        if out.failsafe != self.last_failsafe {
            if let Some(reason) = out.failsafe {
                send(&statustext_of(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    &["failsafe: ", reason.text()],
                ));
            }
            self.last_failsafe = out.failsafe;
        }
        let r = self.rates;
        let [hb, sys, bat, att, pos, odo, dist, obst] = &mut self.slots;
        if hb.due(r.heartbeat_hz, t) {
            send(&heartbeat(out));
        }
        if sys.due(r.sys_status_hz, t) {
            send(&sys_status(report));
        }
        if bat.due(r.battery_status_hz, t) {
            send(&battery_status(report));
        }
        if att.due(r.attitude_hz, t) {
            send(&attitude(report, t));
        }
        if pos.due(r.local_position_hz, t) {
            send(&local_position(report, t));
        }
        if odo.due(r.odometry_hz, t) {
            send(&MavMessage::ODOMETRY(odometry_from_estimate(
                &out.estimate,
                report.body_rates_rad_s,
                t,
            )));
        }
        if let Some(sonar) = report.sonar {
            if dist.due(r.distance_sensor_hz, t) {
                send(&distance_sensor(&sonar, &self.ranges, t));
            }
        }
        if let Some(scan) = report.scan {
            if obst.due(r.obstacle_distance_hz, t) {
                send(&MavMessage::OBSTACLE_DISTANCE(obstacle_distance(
                    scan,
                    self.ranges.lidar,
                    t,
                )));
            }
        }
    }
}

/// A STATUSTEXT; text beyond MAVLink's 50 bytes is cut (every text here is shorter).
pub(crate) fn statustext(severity: MavSeverity, text: &str) -> MavMessage {
    statustext_of(severity, &[text])
}

/// A STATUSTEXT of `parts` joined, built in place (the announcements of every mode change
/// need no allocation).
fn statustext_of(severity: MavSeverity, parts: &[&str]) -> MavMessage {
    let mut text = [0u8; 50];
    let mut len = 0;
    for part in parts {
        let n = part.len().min(text.len() - len);
        text[len..len + n].copy_from_slice(&part.as_bytes()[..n]);
        len += n;
    }
    MavMessage::STATUSTEXT(STATUSTEXT_DATA {
        severity,
        text: text.into(),
        id: 0,
        chunk_seq: 0,
    })
}

fn heartbeat(out: &Outputs) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: custom_mode(out.mode),
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_GENERIC,
        base_mode: base_mode(out.mode),
        system_status: system_status(out.mode, out.failsafe),
        mavlink_version: MAVLINK_VERSION,
    })
}

fn sys_status(report: &TelemetryInput<'_>) -> MavMessage {
    let out = report.outputs;
    let sensors = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_LASER_POSITION
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
    let mut health = sensors;
    match out.failsafe {
        Some(FailsafeReason::LidarLost) => {
            health.remove(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_LASER_POSITION)
        }
        Some(FailsafeReason::BatteryLow | FailsafeReason::BatteryCritical) => {
            health.remove(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY)
        }
        Some(FailsafeReason::EstimateInvalid) => {
            health.remove(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL)
        }
        _ => {}
    }
    if !out.estimate.valid {
        health.remove(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL);
    }
    MavMessage::SYS_STATUS(SYS_STATUS_DATA {
        onboard_control_sensors_present: sensors,
        onboard_control_sensors_enabled: sensors,
        onboard_control_sensors_health: health,
        load: 0,
        voltage_battery: report.battery.map_or(u16::MAX, |b| millivolts(b.voltage_v)),
        current_battery: -1,
        drop_rate_comm: 0,
        errors_comm: 0,
        errors_count1: 0,
        errors_count2: 0,
        errors_count3: 0,
        errors_count4: 0,
        battery_remaining: -1,
        onboard_control_sensors_present_extended: MavSysStatusSensorExtended::empty(),
        onboard_control_sensors_enabled_extended: MavSysStatusSensorExtended::empty(),
        onboard_control_sensors_health_extended: MavSysStatusSensorExtended::empty(),
    })
}

fn battery_status(report: &TelemetryInput<'_>) -> MavMessage {
    let mut voltages = [u16::MAX; 10];
    // Plumbline measures the pack, not cells: the first entry is the pack voltage, which
    // MAVLink allows when cell voltages are unknown.
    if let Some(b) = report.battery {
        voltages[0] = millivolts(b.voltage_v);
    }
    let charge_state = match (report.battery, report.outputs.failsafe) {
        (None, _) => MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_UNDEFINED,
        (_, Some(FailsafeReason::BatteryCritical)) => {
            MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_CRITICAL
        }
        (_, Some(FailsafeReason::BatteryLow)) => {
            MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_LOW
        }
        _ => MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_OK,
    };
    MavMessage::BATTERY_STATUS(BATTERY_STATUS_DATA {
        current_consumed: -1,
        energy_consumed: -1,
        temperature: i16::MAX,
        voltages,
        current_battery: -1,
        id: 0,
        battery_function: MavBatteryFunction::MAV_BATTERY_FUNCTION_ALL,
        mavtype: MavBatteryType::MAV_BATTERY_TYPE_LIPO,
        battery_remaining: -1,
        time_remaining: 0,
        charge_state,
        voltages_ext: [0; 4],
        mode: MavBatteryMode::MAV_BATTERY_MODE_UNKNOWN,
        fault_bitmask: MavBatteryFault::empty(),
    })
}

fn attitude(report: &TelemetryInput<'_>, t_s: f64) -> MavMessage {
    let e = &report.outputs.estimate;
    let [roll, pitch, yaw] = flip_euler(e.roll_rad, e.pitch_rad, e.yaw_rad);
    let [p, q, r] = flip_yz(report.body_rates_rad_s);
    MavMessage::ATTITUDE(ATTITUDE_DATA {
        time_boot_ms: boot_ms(t_s),
        roll,
        pitch,
        yaw,
        rollspeed: p,
        pitchspeed: q,
        yawspeed: r,
    })
}

fn local_position(report: &TelemetryInput<'_>, t_s: f64) -> MavMessage {
    let e = &report.outputs.estimate;
    let [x, y, z] = flip_yz(e.position_m);
    let [vx, vy, vz] = flip_yz(e.velocity_m_s);
    MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
        time_boot_ms: boot_ms(t_s),
        x,
        y,
        z,
        vx,
        vy,
        vz,
    })
}

fn distance_sensor(sonar: &SonarSample, ranges: &SensorRanges, t_s: f64) -> MavMessage {
    let cm = |m: f32| (m * 100.0).round().clamp(0.0, f32::from(u16::MAX)) as u16;
    MavMessage::DISTANCE_SENSOR(DISTANCE_SENSOR_DATA {
        time_boot_ms: boot_ms(t_s),
        min_distance: cm(ranges.sonar_min_m),
        max_distance: cm(ranges.sonar_max_m),
        current_distance: if sonar.range_m.is_finite() {
            cm(sonar.range_m)
        } else {
            u16::MAX
        },
        mavtype: MavDistanceSensor::MAV_DISTANCE_SENSOR_ULTRASOUND,
        id: 0,
        orientation: MavSensorOrientation::MAV_SENSOR_ROTATION_PITCH_270,
        covariance: u8::MAX,
        horizontal_fov: 0.0,
        vertical_fov: 0.0,
        quaternion: [0.0; 4],
        signal_quality: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_50_hz_stream_from_a_200_hz_loop_goes_every_fourth_step() {
        let mut slot = Slot::default();
        let dt = 0.005;
        let sent: Vec<usize> = (0..2000)
            .filter(|&k| slot.due(50.0, k as f64 * dt))
            .collect();
        assert_eq!(sent.len(), 500);
        assert!(
            sent.windows(2).all(|w| w[1] - w[0] == 4),
            "{:?}",
            &sent[..10]
        );
    }

    #[test]
    fn a_stall_does_not_make_a_burst_and_zero_hz_is_off() {
        let mut slot = Slot::default();
        assert!(slot.due(10.0, 0.0));
        assert!(slot.due(10.0, 5.0));
        assert!(!slot.due(10.0, 5.05));
        assert!(slot.due(10.0, 5.1));
        let mut off = Slot::default();
        assert!(!off.due(0.0, 0.0) && !off.due(f64::NAN, 1.0));
    }
}
