//! The closed-loop scenarios through `plumbline sim`: the onboard stack flies the simulated
//! room, and the summary reports what happened. Runs are shortened (the push still lands at
//! t = 20 s) to keep the suite quick; the bounds come from seeds 1-10 (BENCHMARKS.md, "Closed
//! loop") with margin.

use serde_json::{json, Value};
use std::path::PathBuf;
use std::process::{Command, Output};

fn plumbline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(args)
        .output()
        .unwrap()
}

/// Flies `scenario` in the room with the XV-11 and returns the `--json` summary.
fn fly(scenario: &str, seed: &str, duration: &str, extra: &[&str]) -> Value {
    fly_with("xv11", scenario, seed, duration, extra)
}

fn fly_with(lidar: &str, scenario: &str, seed: &str, duration: &str, extra: &[&str]) -> Value {
    let mut args = vec![
        "sim",
        "--world",
        "room",
        "--scenario",
        scenario,
        "--lidar",
        lidar,
        "--controller",
        "pid",
        "--duration",
        duration,
        "--seed",
        seed,
        "--json",
    ];
    args.extend_from_slice(extra);
    let out = plumbline(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap()).unwrap()
}

fn f(summary: &Value, key: &str) -> f64 {
    summary[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing: {summary}"))
}

fn modes(summary: &Value) -> Vec<(f64, String)> {
    summary["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["t_s"].as_f64().unwrap(),
                m["mode"].as_str().unwrap().into(),
            )
        })
        .collect()
}

fn temp_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("plumbline-scenario-{name}-{}", std::process::id()))
}

#[test]
fn hold_rides_out_the_push_and_writes_summary_and_plots() {
    let dir = temp_dir("hold");
    let s = fly("hold", "3", "26", &["--out", dir.to_str().unwrap()]);
    assert_eq!(s["crashed"], false, "{s}");
    assert_eq!(s["landed"], false, "{s}");
    assert!(s["failsafe"].is_null(), "{s}");
    let names: Vec<String> = modes(&s).into_iter().map(|m| m.1).collect();
    assert_eq!(names, ["disarmed", "takeoff", "hold"], "{s}");
    // Seeds 1-10 over 30 s: 4.2-8.1 cm (the estimate sits a few cm off the truth).
    let rms = f(&s, "rms_hold_error_m");
    assert!(rms > 0.0 && rms < 0.12, "{s}");
    assert!(f(&s, "max_hold_error_m") < 0.3, "{s}");
    // The push happened (seeds 1-10: 32-47 cm) and the vehicle came back (0.6-1.3 s).
    assert!(f(&s, "push_max_error_m") > 0.2, "{s}");
    let recovery = f(&s, "recovery_s");
    assert!(recovery < 3.0, "{s}");
    assert!(f(&s, "estimate_drift_m") < 0.15, "{s}");
    assert!(
        f(&s, "energy_wh") > 0.0 && f(&s, "motor_jitter") > 0.0,
        "{s}"
    );
    assert_eq!(f(&s, "sim_seconds"), 26.0);
    for key in ["wall_seconds", "realtime_factor", "rejected_points"] {
        f(&s, key);
    }
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(written["rms_hold_error_m"], s["rms_hold_error_m"]);
    for png in ["position_error.png", "motors.png", "flight.png", "top.png"] {
        let bytes = std::fs::read(dir.join(png)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{png}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn hold_people_rejects_the_walker_unless_told_not_to() {
    let on = fly("hold-people", "3", "30", &[]);
    let off = fly("hold-people", "3", "30", &["--no-rejection"]);
    for s in [&on, &off] {
        assert_eq!(s["crashed"], false, "{s}");
        assert_eq!(s["people"], true, "{s}");
        assert!(f(s, "rms_hold_error_m") < 0.12, "{s}");
    }
    assert_eq!(on["dynamic_rejection"], true);
    assert!(f(&on, "rejected_points") > 0.0, "{on}");
    assert_eq!(off["dynamic_rejection"], false);
    assert_eq!(f(&off, "rejected_points"), 0.0, "{off}");
}

#[test]
fn low_battery_lands_with_the_battery_reason() {
    let s = fly("land-on-low-battery", "2", "25", &[]);
    assert_eq!(s["crashed"], false, "{s}");
    assert_eq!(s["failsafe"], "battery_low", "{s}");
    assert_eq!(s["landed"], true, "{s}");
    let names: Vec<String> = modes(&s).into_iter().map(|m| m.1).collect();
    assert_eq!(
        names,
        ["disarmed", "takeoff", "hold", "land", "disarmed"],
        "{s}"
    );
}

/// The lidar stops at 10 s: after the 1 s timeout the failsafe is raised, after 1 s more on
/// the IMU the vehicle lands, and it touches down without reaching a wall of the room. The
/// summary says so (many seeds are flown in crates/sim/tests/closed_loop.rs).
#[test]
fn lidar_failure_raises_the_lidar_failsafe_and_lands_safely() {
    let s = fly("lidar-failure", "12", "20", &[]);
    assert_eq!(s["failsafe"], "lidar_lost", "{s}");
    assert_eq!(
        (&s["crashed"], &s["landed"]),
        (&json!(false), &json!(true)),
        "{s}"
    );
    let land = modes(&s)
        .into_iter()
        .find(|m| m.1 == "land")
        .unwrap_or_else(|| panic!("never landed: {s}"));
    assert!(land.0 > 11.0 && land.0 <= 12.1, "{s}");
}

#[test]
fn bad_combinations_are_refused_with_a_reason() {
    let cases: [(&[&str], &str); 3] = [
        (
            &["--scenario", "survey", "--controller", "mrac"],
            "flown by the test pilot",
        ),
        (
            &["--scenario", "survey", "--controller", "pid"],
            "flown by the test pilot",
        ),
        (
            &["--scenario", "lidar-failure", "--controller", "test-pilot"],
            "use --controller pid",
        ),
    ];
    for (extra, message) in cases {
        let mut args = vec!["sim", "--world", "room", "--duration", "1"];
        args.extend_from_slice(extra);
        let out = plumbline(&args);
        assert!(!out.status.success(), "{extra:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(message), "{extra:?}: {err}");
    }
}

#[test]
fn the_large_scan_stack_flies_the_utm30lx() {
    let s = fly_with("utm30lx", "hold", "3", "8", &[]);
    assert_eq!(s["lidar"], "utm30lx");
    assert_eq!(s["crashed"], false, "{s}");
    assert!(f(&s, "rms_hold_error_m") < 0.12, "{s}");
}
