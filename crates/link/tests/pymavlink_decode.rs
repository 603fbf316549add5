//! A real ground station decodes what the link sends: pymavlink (installed in `.venv` by
//! scripts/setup.sh) reads a recorded session of telemetry and replies, unsigned and signed, and
//! reports what it saw (`pymavlink_decode.py`).
mod common;

use common::*;
use plumbline_core::flight::params::ParamError;
use plumbline_core::msgs::{
    BatterySample, CommandResult, EstimatedState, FailsafeReason, FlightMode, Outputs, SonarSample,
};
use plumbline_core::scan::Beam;
use plumbline_link::common::{
    MavCmd, MavMessage, MavParamType, COMMAND_LONG_DATA, PARAM_REQUEST_LIST_DATA, PARAM_SET_DATA,
};
use plumbline_link::{
    InboundEvent, Link, LinkConfig, LinkTime, ParameterStore, SigningKey, TelemetryInput,
};
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

struct OneGain(f32);

impl ParameterStore for OneGain {
    fn count(&self) -> usize {
        1
    }
    fn name(&self, index: usize) -> Option<&str> {
        (index == 0).then_some("POS_XY_P")
    }
    fn value(&self, index: usize) -> Option<f32> {
        (index == 0).then_some(self.0)
    }
    fn set(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        match index {
            0 if (0.0..=5.0).contains(&value) => {
                self.0 = value;
                Ok(value)
            }
            0 => Err(ParamError::OutOfRange { min: 0.0, max: 5.0 }),
            _ => Err(ParamError::Unknown),
        }
    }
}

/// Two seconds of a flight at 200 Hz (hold, then a battery failsafe and land), the answer to
/// an arm command and to a parameter list and an out-of-range set.
fn session(key: Option<SigningKey>) -> Vec<u8> {
    let mut link = Link::new(LinkConfig {
        key,
        ..LinkConfig::default()
    });
    let start = unix_now();
    let mut out = Vec::new();
    link.announce(LinkTime::since(start, 0.0), &mut out);
    let scan: Vec<Beam> = (0..360)
        .map(|i| Beam::new((i as f32).to_radians(), 3.0))
        .collect();
    for k in 0..400 {
        let t = k as f64 * 0.005;
        let (mode, failsafe) = if k < 200 {
            (FlightMode::Hold, None)
        } else {
            (FlightMode::Land, Some(FailsafeReason::BatteryLow))
        };
        let outputs = Outputs {
            mode,
            failsafe,
            estimate: EstimatedState {
                position_m: [1.0, 2.0, 1.0],
                yaw_rad: 0.5,
                valid: true,
                ..Default::default()
            },
            ..Default::default()
        };
        let input = TelemetryInput {
            outputs: &outputs,
            body_rates_rad_s: [0.0; 3],
            battery: Some(BatterySample {
                t_s: t,
                voltage_v: 10.5,
            }),
            sonar: Some(SonarSample {
                t_s: t,
                range_m: 1.0,
            }),
            scan: Some(&scan),
        };
        link.telemetry(&input, LinkTime::since(start, t), &mut out);
    }
    // The ground's requests go in signed when the vehicle has a key.
    let mut ground = match key {
        Some(k) => Ground::signed(k.secret),
        None => Ground::unsigned(),
    };
    let mut requests = ground.frame(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: 1.0,
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    }));
    requests.extend(
        ground.frame(&MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
        })),
    );
    requests.extend(ground.frame(&MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: 9.0,
        target_system: 1,
        target_component: 1,
        param_id: "POS_XY_P".into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    })));
    let now = LinkTime::since(start, 2.0);
    let (events, replies) = feed(&mut link, &requests, now);
    assert!(replies.is_empty());
    let mut store = OneGain(1.0);
    for event in events {
        match event {
            InboundEvent::Command { ack: Some(to), .. } => {
                link.acknowledge(to, CommandResult::Accepted, now, &mut out)
            }
            InboundEvent::Param { request, from } => {
                link.serve_param(&request, from, &mut store, now, &mut out)
            }
            other => panic!("{other:?}"),
        }
    }
    out
}

fn decode_with_pymavlink(bytes: &[u8], key: Option<[u8; 32]>) -> Value {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let python = root.join(".venv/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run scripts/setup.sh to install pymavlink for the real-client tests",
        python.display()
    );
    let file = std::env::temp_dir().join(format!(
        "plumbline-link-{}-{}.bin",
        std::process::id(),
        key.is_some()
    ));
    std::fs::write(&file, bytes).unwrap();
    let mut cmd = Command::new(python);
    cmd.arg(root.join("crates/link/tests/pymavlink_decode.py"))
        .arg(&file);
    if let Some(k) = key {
        cmd.arg(k.iter().map(|b| format!("{b:02x}")).collect::<String>());
    }
    let output = cmd.output().unwrap();
    let _ = std::fs::remove_file(&file);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

fn check(report: &Value) {
    let counts = &report["counts"];
    assert_eq!(report["bad"], 0, "{report}");
    // 2 s at 200 Hz: the 1 Hz streams twice, 50 Hz a hundred times, 10 Hz twenty.
    for (name, n) in [
        ("HEARTBEAT", 2),
        ("SYS_STATUS", 2),
        ("BATTERY_STATUS", 2),
        ("ATTITUDE", 100),
        ("LOCAL_POSITION_NED", 100),
        ("ODOMETRY", 20),
        ("DISTANCE_SENSOR", 20),
        ("OBSTACLE_DISTANCE", 20),
        ("COMMAND_ACK", 1),
        ("PARAM_ERROR", 1),
    ] {
        assert_eq!(counts[name], n, "{name}: {report}");
    }
    let f = &report["fields"];
    assert_eq!(f["HEARTBEAT"]["custom_mode"], 2);
    assert_eq!(f["HEARTBEAT"]["type"], 2, "MAV_TYPE_QUADROTOR");
    assert_eq!(f["LOCAL_POSITION_NED"]["y"], -2.0);
    assert_eq!(f["LOCAL_POSITION_NED"]["z"], -1.0);
    assert_eq!(f["ATTITUDE"]["yaw"], -0.5);
    assert_eq!(f["ODOMETRY"]["frame_id"], 1, "MAV_FRAME_LOCAL_NED");
    assert_eq!(f["ODOMETRY"]["child_frame_id"], 12, "MAV_FRAME_BODY_FRD");
    assert_eq!(f["OBSTACLE_DISTANCE"]["distances"][0], 300);
    assert_eq!(f["OBSTACLE_DISTANCE"]["increment_f"], 5.0);
    assert_eq!(f["OBSTACLE_DISTANCE"]["frame"], 12);
    assert_eq!(f["DISTANCE_SENSOR"]["current_distance"], 100);
    assert_eq!(f["DISTANCE_SENSOR"]["orientation"], 25, "pointing down");
    assert_eq!(f["BATTERY_STATUS"]["voltages"][0], 10500);
    let texts: Vec<&str> = report["texts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    assert_eq!(
        &texts[1..4],
        ["mode hold", "mode land", "failsafe: battery low"]
    );
    assert_eq!(texts[4], "POS_XY_P 9: value outside [0, 5]");
    assert_eq!(report["acks"][0], serde_json::json!([400, 0, 255]));
    // The list answer, then the unchanged value after the refused set.
    assert_eq!(
        report["params"],
        serde_json::json!([["POS_XY_P", 1.0, 0, 1], ["POS_XY_P", 1.0, 0, 1]])
    );
    assert_eq!(report["param_errors"], serde_json::json!([["POS_XY_P", 2]]));
}

#[test]
fn pymavlink_decodes_every_frame_of_an_unsigned_session() {
    let report = decode_with_pymavlink(&session(None), None);
    check(&report);
    assert!(report["texts"][0]
        .as_str()
        .unwrap()
        .starts_with("link unsigned"));
}

#[test]
fn pymavlink_accepts_the_signed_session_with_the_key_and_refuses_it_without() {
    let key = SigningKey {
        secret: KEY,
        link_id: 2,
    };
    let bytes = session(Some(key));
    let report = decode_with_pymavlink(&bytes, Some(KEY));
    check(&report);
    assert_eq!(
        (&report["rejected_signatures"], &report["bad_signatures"]),
        (&0.into(), &0.into())
    );
    let frames: u64 = report["counts"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(report["good_signatures"], frames);
    let wrong = decode_with_pymavlink(&bytes, Some([9; 32]));
    assert_eq!(wrong["good_signatures"], 0);
    assert_eq!(wrong["bad_signatures"].as_u64().unwrap(), frames);
    assert_eq!(wrong["counts"], serde_json::json!({}));
}
