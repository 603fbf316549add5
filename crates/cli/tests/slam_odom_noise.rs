//! `plumbline slam --odom-prior --odom-noise`: the odometry combined with each match by their
//! covariances; a bad spread is refused with a message naming the value, before any work.

use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(args)
        .output()
        .unwrap()
}

fn excerpt() -> String {
    format!(
        "{}/../../data/intel-excerpt.clf",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn a_bad_odometry_spread_is_refused_with_what_to_give() {
    let log = excerpt();
    for (noise, says) in [
        ("0.01,0.05,0.002", "found 3 values"),
        ("0.01,x,0.002,0.05", "give four numbers"),
        ("0,0.05,0.002,0.05", "FLOOR_M is 0"),
        ("0.01,0.05,0.002,-1", "PER_RAD is -1"),
        ("0.01,NaN,0.002,0.05", "PER_M is NaN"),
    ] {
        let out = run(&["slam", &log, "--odom-prior", "--odom-noise", noise]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{noise}: accepted");
        assert!(
            err.contains("--odom-noise") && err.contains(says),
            "{noise}: {err}"
        );
    }
    // Without the odometry there is nothing to combine.
    let out = run(&["slam", &log, "--odom-noise", "0.01,0.05,0.002,0.05"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--odom-prior"));
}

#[test]
fn the_odometry_combined_by_covariance_still_tracks_the_excerpt() {
    let log = excerpt();
    let out = run(&[
        "slam",
        &log,
        "--odom-prior",
        "--odom-noise",
        "0.05,0.1,0.02,0.1",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let summary: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    assert!(summary["scans"].as_u64().unwrap() > 0);
    assert_eq!(summary["lost_intervals"].as_u64(), Some(0), "{summary}");
}
