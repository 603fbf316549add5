//! `plumbline sim --mavlink` with pymavlink as the ground station (tests/mavlink/ground_station.py,
//! run with the Python of the repository's `.venv`, which scripts/setup.sh makes): telemetry
//! fields and rates, parameters, a signed kill, unsigned commands refused, garbage and a flood
//! survived, and a 10-minute flight at 50 Hz without a lost message. Loopback UDP only.

mod support;

use std::path::PathBuf;
use std::process::Command;
use support::BIN;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs one case of the pymavlink script and fails with its output unless it passes.
fn ground_station(case: &str) {
    let python = repo().join(".venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run scripts/setup.sh to install the pymavlink ground station",
        python.display()
    );
    let script = repo().join("tests/mavlink/ground_station.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(BIN)
        .arg(case)
        .output()
        .expect("start python");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "pymavlink {case} failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
}

#[test]
fn pymavlink_decodes_every_message_at_its_rate() {
    ground_station("telemetry");
}

#[test]
fn pymavlink_sets_parameters_kills_with_the_key_and_is_refused_without() {
    ground_station("commands");
}

#[test]
fn ten_minutes_at_50_hz_lose_no_message() {
    ground_station("endurance");
}
