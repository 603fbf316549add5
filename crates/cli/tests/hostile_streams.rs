//! Hostile inputs, bounded memory and streaming: endless or enormous inputs end with a clear
//! error or stream through with bounded memory, and results are written as they are computed.
//! Runs that could read an endless input into memory are capped at 1 GiB of address space.

mod support;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use support::{excerpt, p, run, run_capped, scratch, stderr, BIN};

#[test]
fn decoding_an_endless_input_stops_with_a_clear_error() {
    for device in ["xv11", "xv11-old", "urg", "rplidar"] {
        let out = run_capped(&["lidar", "decode", "--device", device, "/dev/zero"]);
        assert!(!out.status.success(), "{device}");
        let err = stderr(&out);
        assert!(
            err.contains(&format!("no valid {device} frame")) && err.contains("wrong --device"),
            "{device}: {err}"
        );
    }
}

#[test]
fn reading_a_log_without_line_breaks_stops_with_a_clear_error() {
    let out = run_capped(&["odometry", "/dev/zero"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("/dev/zero:1: line is longer than 8 MiB"),
        "{err}"
    );
}

/// The excerpt's trajectory, computed alone.
fn excerpt_trajectory(dir: &std::path::Path) -> Vec<String> {
    let traj = dir.join("excerpt.traj");
    let out = run(&["odometry", p(&excerpt()), "--out", p(&traj)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&traj).unwrap();
    text.lines().map(str::to_string).collect()
}

#[test]
fn odometry_writes_each_pose_as_it_goes_and_a_killed_run_keeps_them() {
    let dir = scratch("killed-odometry");
    let expected = excerpt_trajectory(&dir);
    // The excerpt four times over: a run long enough to be stopped part way.
    let text = std::fs::read(excerpt()).unwrap();
    let log = dir.join("long.clf");
    std::fs::write(&log, text.repeat(4)).unwrap();
    let traj = dir.join("long.traj");
    let mut child = Command::new(BIN)
        .args(["odometry", p(&log), "--out", p(&traj)])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let lines = loop {
        let lines = std::fs::read_to_string(&traj)
            .unwrap_or_default()
            .lines()
            .count();
        if lines > expected.len() {
            break lines;
        }
        let done = child.try_wait().unwrap();
        assert!(
            done.is_none(),
            "the run ended before its trajectory showed more than {} poses",
            expected.len()
        );
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no poses in 300 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = std::fs::read_to_string(&traj).unwrap();
    let kept: Vec<&str> = kept.lines().collect();
    assert!(kept.len() >= lines && kept.len() < 4 * expected.len());
    assert_eq!(kept[..expected.len()], expected[..]);
}

#[test]
fn a_bad_line_late_in_a_log_keeps_the_poses_before_it_and_says_where_they_are() {
    let dir = scratch("late-bad-line");
    let expected = excerpt_trajectory(&dir);
    let mut text = std::fs::read_to_string(excerpt()).unwrap();
    text.push_str("FLASER 3 1.0 2.0\n");
    let log = dir.join("bad.clf");
    std::fs::write(&log, &text).unwrap();
    let traj = dir.join("bad.traj");
    let out = run(&["odometry", p(&log), "--out", p(&traj)]);
    assert!(!out.status.success());
    let err = stderr(&out);
    let lines = text.lines().count();
    assert!(
        err.contains(&format!(
            "bad.clf:{lines}: FLASER: 3 readings make 12 fields"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "the trajectory of the {} scan(s) before it is in",
            expected.len()
        )),
        "{err}"
    );
    let kept = std::fs::read_to_string(&traj).unwrap();
    assert_eq!(kept.lines().collect::<Vec<_>>(), expected);
}
