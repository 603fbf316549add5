//! Hostile inputs, data loss: no command may destroy a file it was not asked to write, nor
//! lose what it recorded. Each test runs the real binary.

mod support;

use plumbline_io::carmen::{read_log, ReadOptions};
use plumbline_io::serial::{decode_capture, Device};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;
use support::{capture, entries, excerpt, last_json, p, run, scratch, socat_pair, stderr, BIN};

/// A directory holding `precious.bin` (a real capture) and `precious.bin.log` (text).
fn precious(dir: &Path) -> (Vec<u8>, &'static str) {
    let bytes = std::fs::read(capture()).unwrap();
    std::fs::write(dir.join("precious.bin"), &bytes).unwrap();
    std::fs::write(dir.join("precious.bin.log"), "the old log\n").unwrap();
    (bytes, "the old log\n")
}

fn assert_untouched(dir: &Path, bytes: &[u8], log: &str) {
    assert_eq!(std::fs::read(dir.join("precious.bin")).unwrap(), bytes);
    assert_eq!(
        std::fs::read_to_string(dir.join("precious.bin.log")).unwrap(),
        log
    );
    assert_eq!(entries(dir), ["precious.bin", "precious.bin.log"]);
}

/// Records from `port` into `dir/precious.bin`, ending after 0.3 s of silence.
fn record_into(dir: &Path, port: &str) -> std::process::Output {
    let raw = dir.join("precious.bin");
    let args = ["lidar", "record", "--device", "xv11", "--port", port];
    run(&[&args[..], &["--idle-timeout", "0.3", "--out", p(&raw)]].concat())
}

#[test]
fn a_port_that_cannot_be_opened_leaves_existing_files_untouched() {
    let dir = scratch("no-port");
    let (bytes, log) = precious(&dir);
    let out = record_into(&dir, "/dev/plumbline-no-such-port");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("cannot open"), "{}", stderr(&out));
    assert_untouched(&dir, &bytes, log);
}

#[test]
fn a_port_that_never_sends_leaves_existing_files_untouched() {
    let dir = scratch("silent-port");
    let Some(socat) = socat_pair(&dir, "a_port_that_never_sends") else {
        return;
    };
    let files = dir.join("files");
    std::fs::create_dir(&files).unwrap();
    let (bytes, log) = precious(&files);
    let out = record_into(&files, p(&socat.b));
    assert!(!out.status.success());
    assert!(stderr(&out).contains("no data for"), "{}", stderr(&out));
    assert_untouched(&files, &bytes, log);
}

#[test]
fn record_refuses_a_capture_and_log_that_are_one_file() {
    let dir = scratch("record-alias");
    let x = dir.join("x");
    std::fs::create_dir(dir.join("sub")).unwrap();
    for log in [x.clone(), dir.join("sub/../x")] {
        let out = run(&[
            "lidar",
            "record",
            "--device",
            "xv11",
            "--port",
            "/dev/plumbline-no-such-port",
            "--out",
            p(&x),
            "--log",
            p(&log),
        ]);
        assert!(!out.status.success());
        assert!(
            stderr(&out).contains("--out and --log name the same file"),
            "{}",
            stderr(&out)
        );
    }
    assert_eq!(entries(&dir), ["sub"]);
}

#[test]
fn decode_refuses_an_output_that_is_its_input_by_any_name() {
    let dir = scratch("decode-alias");
    let bytes = std::fs::read(capture()).unwrap();
    let input = dir.join("cap.bin");
    std::fs::write(&input, &bytes).unwrap();
    std::fs::hard_link(&input, dir.join("hard.bin")).unwrap();
    std::os::unix::fs::symlink(&input, dir.join("soft.bin")).unwrap();
    for alias in ["cap.bin", "hard.bin", "soft.bin", "./cap.bin"] {
        let out = run(&[
            "lidar",
            "decode",
            "--device",
            "xv11",
            p(&input),
            "--out",
            p(&dir.join(alias)),
        ]);
        assert!(!out.status.success(), "{alias}");
        assert!(
            stderr(&out).contains("same file as the input CAPTURE"),
            "{alias}: {}",
            stderr(&out)
        );
        assert_eq!(std::fs::read(&input).unwrap(), bytes, "{alias}");
    }
}

#[test]
fn odometry_refuses_outputs_that_are_its_log_or_each_other() {
    let dir = scratch("odometry-alias");
    let log = dir.join("run.clf");
    let text = std::fs::read(excerpt()).unwrap();
    std::fs::write(&log, &text).unwrap();
    std::os::unix::fs::symlink(&log, dir.join("link.clf")).unwrap();
    let out = run(&["odometry", p(&log), "--out", p(&dir.join("link.clf"))]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("same file as the input LOG"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read(&log).unwrap(), text);
    let png = dir.join("t.png");
    let out = run(&["odometry", p(&log), "--out", p(&png), "--plot", p(&png)]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("--out and --plot name the same file"),
        "{}",
        stderr(&out)
    );
    assert!(!png.exists());
}

#[test]
fn a_recording_cut_by_a_vanishing_port_keeps_its_last_revolution_and_says_what_it_kept() {
    let dir = scratch("cut");
    let Some(socat) = socat_pair(&dir, "a_recording_cut_by_a_vanishing_port") else {
        return;
    };
    let raw = dir.join("cut.bin");
    // A long idle timeout: the recording can only end by the port failing.
    let rec = Command::new(BIN)
        .args(["lidar", "record", "--device", "xv11", "--port", p(&socat.b)])
        .args([
            "--duration",
            "30",
            "--idle-timeout",
            "20",
            "--json",
            "--out",
            p(&raw),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let bytes = std::fs::read(capture()).unwrap();
    // 20,000 bytes end part way through the 11th revolution.
    std::fs::write(&socat.a, &bytes[..20_000]).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    drop(socat);
    let out = rec.wait_with_output().unwrap();
    assert!(!out.status.success(), "a cut recording is a failure");
    assert!(
        stderr(&out).contains("the recording up to then is kept"),
        "{}",
        stderr(&out)
    );
    let summary = last_json(&out);
    assert!(summary["failure"].as_str().is_some(), "{summary}");
    let kept = std::fs::read(&raw).unwrap();
    assert_eq!(kept, bytes[..20_000]);
    let (scans, _) = decode_capture(Device::Xv11, &kept, 115_200).unwrap();
    let log = read_log(&dir.join("cut.bin.log"), &ReadOptions::default()).unwrap();
    assert_eq!(
        log.scans.len(),
        scans.len(),
        "the partial revolution is lost"
    );
    assert_eq!(summary["revolutions"], scans.len());
}

#[test]
fn sim_refuses_outputs_that_would_overwrite_its_world_or_log() {
    let dir = scratch("sim-alias");
    let world = dir.join("truth.txt");
    let room = "start 1 1 0\noutline 0 0 6 0 6 4.5 0 4.5\npath 1 1 4 1\n";
    std::fs::write(&world, room).unwrap();
    let out = support::fly(&world, Some(&dir));
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("same file as the input --world"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read_to_string(&world).unwrap(), room);
    assert_eq!(entries(&dir), ["truth.txt"]);

    let log = dir.join("intel.world");
    let text = std::fs::read(excerpt()).unwrap();
    std::fs::write(&log, &text).unwrap();
    let out = run(&["sim", "--rasterize", p(&log), "--out", p(&dir)]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("same file as the input --rasterize"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read(&log).unwrap(), text);
}
