//! `plumbline sim --mavlink` with pymavlink as the ground station (tests/mavlink/ground_station.py,
//! run with the Python of the repository's `.venv`, which scripts/setup.sh makes): telemetry
//! fields and rates, parameters, a signed kill, unsigned commands refused, garbage and a flood
//! survived, and a 10-minute flight at 50 Hz without a lost message. Loopback UDP only.

mod support;

use support::{venv_script, BIN};

/// Runs one case of the pymavlink script.
fn ground_station(case: &str) {
    venv_script(
        "tests/mavlink/ground_station.py",
        &[BIN, case],
        "the pymavlink ground station",
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
