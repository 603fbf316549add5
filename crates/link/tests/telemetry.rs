//! Vehicle to ground: what a ground station decodes from the telemetry, and how often.
mod common;

use common::*;
use plumbline_core::msgs::{
    BatterySample, EstimatedState, FailsafeReason, FlightMode, Outputs, SonarSample,
};
use plumbline_core::scan::Beam;
use plumbline_link::common::{MavBatteryChargeState, MavMessage, MavModeFlag, MavState};
use plumbline_link::{Link, LinkConfig, LinkTime, TelemetryInput};
use std::collections::BTreeMap;

fn outputs(mode: FlightMode, failsafe: Option<FailsafeReason>) -> Outputs {
    Outputs {
        mode,
        failsafe,
        estimate: EstimatedState {
            position_m: [1.0, 2.0, 1.5],
            velocity_m_s: [0.5, 0.0, 0.0],
            yaw_rad: 0.3,
            valid: true,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn beams() -> Vec<Beam> {
    (0..360)
        .map(|i| Beam::new((i as f32).to_radians(), 2.0))
        .collect()
}

fn input<'a>(out: &'a Outputs, scan: &'a [Beam]) -> TelemetryInput<'a> {
    TelemetryInput {
        outputs: out,
        body_rates_rad_s: [0.0, 0.0, 0.1],
        battery: Some(BatterySample {
            t_s: 0.0,
            voltage_v: 11.1,
        }),
        sonar: Some(SonarSample {
            t_s: 0.0,
            range_m: 1.5,
        }),
        scan: Some(scan),
    }
}

fn names(bytes: &[u8]) -> BTreeMap<&'static str, usize> {
    let mut counts = BTreeMap::new();
    for (_, m) in decode_all(bytes, None) {
        *counts
            .entry(mavlink::Message::message_name(&m))
            .or_insert(0) += 1;
    }
    counts
}

#[test]
fn the_first_step_sends_every_message_with_the_real_state() {
    let out = outputs(FlightMode::Hold, None);
    let scan = beams();
    let mut link = Link::new(LinkConfig::default());
    let mut bytes = Vec::new();
    link.telemetry(&input(&out, &scan), LinkTime::since(0.0, 0.0), &mut bytes);
    let decoded = decode_all(&bytes, None);
    let got: Vec<&str> = decoded
        .iter()
        .map(|(_, m)| mavlink::Message::message_name(m))
        .collect();
    assert_eq!(
        got,
        [
            "STATUSTEXT",
            "HEARTBEAT",
            "SYS_STATUS",
            "BATTERY_STATUS",
            "ATTITUDE",
            "LOCAL_POSITION_NED",
            "ODOMETRY",
            "DISTANCE_SENSOR",
            "OBSTACLE_DISTANCE"
        ]
    );
    for (header, m) in &decoded {
        assert_eq!((header.system_id, header.component_id), (1, 1));
        match m {
            MavMessage::STATUSTEXT(t) => assert_eq!(t.text.to_str().unwrap(), "mode hold"),
            MavMessage::HEARTBEAT(h) => {
                assert_eq!(h.custom_mode, 2);
                assert!(h
                    .base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED));
                assert_eq!(h.system_status, MavState::MAV_STATE_ACTIVE);
            }
            MavMessage::SYS_STATUS(s) => assert_eq!(s.voltage_battery, 11100),
            MavMessage::BATTERY_STATUS(b) => {
                assert_eq!(b.voltages[0], 11100);
                assert_eq!(
                    b.charge_state,
                    MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_OK
                );
            }
            MavMessage::ATTITUDE(a) => assert_eq!((a.yaw, a.yawspeed), (-0.3, -0.1)),
            MavMessage::LOCAL_POSITION_NED(p) => {
                assert_eq!((p.x, p.y, p.z, p.vx), (1.0, -2.0, -1.5, 0.5))
            }
            MavMessage::ODOMETRY(o) => assert_eq!((o.x, o.y), (1.0, -2.0)),
            MavMessage::DISTANCE_SENSOR(d) => assert_eq!(d.current_distance, 150),
            MavMessage::OBSTACLE_DISTANCE(o) => assert!(o.distances.iter().all(|&d| d == 200)),
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn streams_keep_their_rates_over_ten_seconds_at_200_hz() {
    let out = outputs(FlightMode::Hold, None);
    let scan = beams();
    let mut link = Link::new(LinkConfig::default());
    let mut bytes = Vec::new();
    for k in 0..2000 {
        let t = k as f64 * 0.005;
        link.telemetry(&input(&out, &scan), LinkTime::since(0.0, t), &mut bytes);
    }
    let counts = names(&bytes);
    assert_eq!(counts["HEARTBEAT"], 10);
    assert_eq!(counts["SYS_STATUS"], 10);
    assert_eq!(counts["BATTERY_STATUS"], 10);
    assert_eq!(counts["ATTITUDE"], 500);
    assert_eq!(counts["LOCAL_POSITION_NED"], 500);
    assert_eq!(counts["ODOMETRY"], 100);
    assert_eq!(counts["DISTANCE_SENSOR"], 100);
    assert_eq!(counts["OBSTACLE_DISTANCE"], 100);
    assert_eq!(counts["STATUSTEXT"], 1, "the mode did not change");
}

#[test]
fn mode_changes_and_failsafes_are_announced_once_each() {
    let scan = beams();
    let mut link = Link::new(LinkConfig::default());
    let mut bytes = Vec::new();
    let steps = [
        outputs(FlightMode::Hold, None),
        outputs(FlightMode::Hold, None),
        outputs(FlightMode::Land, Some(FailsafeReason::BatteryLow)),
        outputs(FlightMode::Land, Some(FailsafeReason::BatteryLow)),
        outputs(FlightMode::Killed, Some(FailsafeReason::KillSwitch)),
    ];
    for (k, out) in steps.iter().enumerate() {
        link.telemetry(
            &input(out, &scan),
            LinkTime::since(0.0, k as f64 * 0.01),
            &mut bytes,
        );
    }
    let texts: Vec<String> = decode_all(&bytes, None)
        .into_iter()
        .filter_map(|(_, m)| match m {
            MavMessage::STATUSTEXT(t) => Some(t.text.to_str().unwrap().to_owned()),
            _ => None,
        })
        .collect();
    assert_eq!(
        texts,
        [
            "mode hold",
            "mode land",
            "failsafe: battery low",
            "mode killed",
            "failsafe: kill switch"
        ]
    );
}

#[test]
fn sequence_numbers_count_every_frame() {
    let out = outputs(FlightMode::Disarmed, None);
    let mut link = Link::new(LinkConfig::default());
    let mut bytes = Vec::new();
    for k in 0..100 {
        link.telemetry(
            &input(&out, &[]),
            LinkTime::since(0.0, k as f64 * 0.02),
            &mut bytes,
        );
    }
    let seqs: Vec<u8> = decode_all(&bytes, None)
        .iter()
        .map(|(h, _)| h.sequence)
        .collect();
    assert!(seqs.len() > 256);
    assert!(seqs.windows(2).all(|w| w[1] == w[0].wrapping_add(1)));
}
