//! `plumbline sim --mavlink` with pymavlink as the ground station (tests/mavlink/ground_station.py,
//! run with the Python of the repository's `.venv`, which scripts/setup.sh makes): telemetry
//! fields and rates, parameters, a signed kill, unsigned commands refused, garbage and a flood
//! survived, and a 10-minute flight at 50 Hz without a lost message. Loopback UDP only.
//! Without Python: a link nobody talks to leaves the flight as it is, and bad options are
//! refused with what to do.

mod support;

use std::net::UdpSocket;
use support::{last_json, run, stderr, venv_script, BIN};

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

#[test]
fn a_link_nobody_talks_to_leaves_the_flight_bit_identical() {
    // A bound socket that never reads: the vehicle's datagrams pile up unread there.
    let sink = UdpSocket::bind("127.0.0.1:0").unwrap();
    let endpoint = format!("udpout:{}", sink.local_addr().unwrap());
    let args = [
        "sim",
        "--scenario",
        "hold",
        "--world",
        "room",
        "--duration",
        "8",
        "--json",
    ];
    let alone = run(&args);
    let linked = run(&[&args[..], &["--mavlink", &endpoint]].concat());
    let (mut a, mut b) = (last_json(&alone), last_json(&linked));
    let link = b["mavlink"].take();
    for s in [&mut a, &mut b] {
        let map = s.as_object_mut().unwrap();
        for k in ["wall_seconds", "realtime_factor", "mavlink"] {
            map.remove(k);
        }
    }
    assert_eq!(a, b, "the link changed the flight");
    assert!(link["sent_messages"].as_u64().unwrap() > 800, "{link}");
    assert_eq!(link["dropped_messages"], 0, "{link}");
    assert_eq!(link["signed"], false);
    assert_eq!(link["endpoint"], endpoint.as_str());
}

#[test]
fn bad_link_options_are_refused_with_what_to_do() {
    for (args, says) in [
        (
            vec!["--mavlink", "udp:127.0.0.1:14550"],
            "unknown kind `udp`",
        ),
        (
            vec!["--mavlink", "udpout:127.0.0.1"],
            "expected udpout:HOST:PORT",
        ),
        (
            vec![
                "--mavlink",
                "udpout:127.0.0.1:14550",
                "--mavlink-key",
                "abc",
            ],
            "64 hexadecimal digits",
        ),
        (vec!["--mavlink-key", "00"], "--mavlink <ENDPOINT>"),
        (vec!["--realtime", "0"], "(0, 1000]"),
        (
            vec!["--controller", "test-pilot", "--realtime"],
            "flight by the onboard stack",
        ),
    ] {
        let base = ["sim", "--scenario", "hold", "--duration", "1"];
        let out = run(&[&base[..], &args[..]].concat());
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
    }
}
