//! `plumbline lidar` end to end: the real XV-11 capture decoded to a CARMEN log and read back,
//! bad input as clear errors, and recording through a virtual serial port pair (socat).

mod support;

use plumbline_io::carmen::{read_log, ReadOptions};
use plumbline_io::serial::{decode_capture, Device};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use support::socat_pair;

const BIN: &str = env!("CARGO_BIN_EXE_plumbline");
const CAPTURES: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/captures/neato-xv11"
);

fn capture(name: &str) -> PathBuf {
    Path::new(CAPTURES).join(name)
}

fn tmp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plumbline-lidar-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `plumbline` with whitespace-separated arguments (the paths used here have no spaces).
fn run(args: &str) -> Output {
    Command::new(BIN)
        .args(args.split_whitespace())
        .output()
        .unwrap()
}

fn last_json(out: &Output) -> serde_json::Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap()
}

#[test]
fn decode_writes_a_carmen_log_that_reads_back() {
    let dir = tmp_dir("decode");
    let log = dir.join("hib.log");
    let cap = capture("hand_in_box.bin");
    let out = run(&format!(
        "lidar decode --device xv11 {} --out {} --json",
        cap.display(),
        log.display()
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = last_json(&out);
    assert_eq!(s["packets_ok"], 11451);
    assert_eq!(s["bad_checksum"], 1);
    assert_eq!(s["revolutions"], 161);
    let rpm = s["rpm_median"].as_f64().unwrap();
    assert!((290.0..300.0).contains(&rpm), "rpm_median {rpm}");
    let back = read_log(&log, &ReadOptions::default()).unwrap();
    assert_eq!(back.scans.len(), 161);
    let invalid: u64 = back
        .scans
        .iter()
        .map(|r| r.valid.iter().filter(|v| !**v).count() as u64)
        .sum();
    assert_eq!(serde_json::Value::from(invalid), s["invalid_beams"]);
    // Stamped by the device's own rate: one revolution lasts 60 / RPM, so the steady part
    // (about 297 RPM) advances 0.202 s a scan and revolution 60 starts about 12 s in, not the
    // 10.2 s that the 115200-baud line rate would claim (the XV-11 pauses between packets).
    let t: Vec<f64> = back.scans.iter().map(|r| r.timestamp_s).collect();
    assert!((11.8..12.3).contains(&t[60]), "t60 {}", t[60]);
    assert!(t[10..100]
        .windows(2)
        .all(|w| (0.195..0.21).contains(&(w[1] - w[0]))));
    assert!(t.windows(2).all(|w| w[1] >= w[0]));
    assert!((back.scans[0].start_angle_rad + 179f32.to_radians()).abs() < 1e-5);
}

#[test]
fn wrong_device_and_missing_file_are_clear_errors() {
    let cap = capture("hand_in_box.bin");
    let out = run(&format!("lidar decode --device xv11-old {}", cap.display()));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("hand_in_box.bin: 252146 bytes but no valid xv11-old frame"),
        "{err}"
    );
    let out = run("lidar decode --device xv11 /no/such/capture.bin");
    assert!(String::from_utf8_lossy(&out.stderr).contains("/no/such/capture.bin"));
    let out = run("lidar record --device xv11 --port /dev/plumbline-none --out /dev/null");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/dev/plumbline-none: cannot open"));
}

#[test]
fn plot_draws_a_png() {
    let png = tmp_dir("plot").join("rev.png");
    let cap = capture("hand_in_box.bin");
    let out = run(&format!(
        "lidar plot --device xv11 {} --revolution 60 --out {}",
        cap.display(),
        png.display()
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let out = run(&format!(
        "lidar plot --device xv11 {} --revolution 999 --out {}",
        cap.display(),
        png.display()
    ));
    assert!(String::from_utf8_lossy(&out.stderr).contains("revolution 999 asked, 161 decoded"));
}

#[test]
fn record_through_a_virtual_serial_port_equals_the_file_decode() {
    let dir = tmp_dir("record");
    let Some(socat) = socat_pair(&dir, "record_through_a_virtual_serial_port") else {
        return;
    };
    let raw = dir.join("rec.bin");
    let args = format!(
        "lidar record --device xv11 --port {} --duration 8 --idle-timeout 1 --json --out {}",
        socat.b.display(),
        raw.display()
    );
    let rec = Command::new(BIN)
        .args(args.split_whitespace())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let bytes = std::fs::read(capture("hand_in_box.bin")).unwrap();
    std::fs::write(&socat.a, &bytes).unwrap();
    let out = rec.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(&raw).unwrap(),
        bytes,
        "raw capture differs from what was sent"
    );
    let summary = last_json(&out);
    assert_eq!(summary["packets_ok"], 11451);
    // The capture is sent in well under a second; the silence after it ends the recording.
    assert_eq!(summary["stopped_by_silence"], true);
    let log = read_log(&dir.join("rec.bin.log"), &ReadOptions::default()).unwrap();
    let (file_scans, _) = decode_capture(Device::Xv11, &bytes, 115_200).unwrap();
    assert_eq!(log.scans.len(), file_scans.len());
    for (got, want) in log.scans.iter().zip(&file_scans) {
        assert_eq!(got.valid, want.record.valid);
        let close = got
            .ranges_m
            .iter()
            .zip(&want.record.ranges_m)
            .zip(&got.valid);
        assert!(close
            .filter(|(_, ok)| **ok)
            .all(|((g, w), _)| (g - w).abs() < 5e-4));
    }
}

#[test]
fn a_silent_port_times_out_with_a_clear_error() {
    let dir = tmp_dir("silent");
    let Some(socat) = socat_pair(&dir, "a_silent_port_times_out") else {
        return;
    };
    let start = Instant::now();
    let out = run(&format!(
        "lidar record --device xv11 --port {} --duration 10 --idle-timeout 0.5 --out {}",
        socat.b.display(),
        dir.join("x.bin").display()
    ));
    assert!(!out.status.success());
    assert!(start.elapsed() < Duration::from_secs(5));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no data for 0.5 s"));
}

/// Plays the sensor on the far end of the pty pair: what it receives arrives on the channel.
fn device_end(path: &Path) -> (std::fs::File, std::sync::mpsc::Receiver<Vec<u8>>) {
    use std::io::Read;
    let dev = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .unwrap();
    let mut reader = dev.try_clone().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 256];
        while let Ok(n @ 1..) = reader.read(&mut buf) {
            if tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    (dev, rx)
}

fn receive_line(rx: &std::sync::mpsc::Receiver<Vec<u8>>) -> Vec<u8> {
    let mut got = Vec::new();
    while !got.ends_with(b"\n") {
        got.extend(
            rx.recv_timeout(Duration::from_secs(5))
                .expect("nothing received within 5 s"),
        );
    }
    got
}

#[test]
fn record_starts_and_stops_a_urg_stream_and_decodes_its_reply() {
    use std::io::Write;
    let dir = tmp_dir("urg");
    let Some(socat) = socat_pair(&dir, "record_starts_and_stops_a_urg_stream") else {
        return;
    };
    let (mut dev, rx) = device_end(&socat.a);
    let args = format!(
        "lidar record --device urg --port {} --duration 8 --idle-timeout 1 --json --out {}",
        socat.b.display(),
        dir.join("urg.bin").display()
    );
    let rec = Command::new(BIN)
        .args(args.split_whitespace())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    assert_eq!(receive_line(&rx), b"MD0044072500000\n");
    // One GS reply holding the specification's example value twice (1234 mm = "CB").
    dev.write_all(b"GS0044004500\n00P\n00000\nCBCB:\n\n")
        .unwrap();
    let out = rec.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(receive_line(&rx), b"QT\n");
    let summary = last_json(&out);
    assert_eq!(
        (
            summary["revolutions"].as_u64(),
            summary["invalid_beams"].as_u64()
        ),
        (Some(1), Some(0))
    );
}

#[test]
fn a_port_that_disappears_ends_the_recording_within_the_idle_timeout() {
    let dir = tmp_dir("vanish");
    let Some(socat) = socat_pair(&dir, "a_port_that_disappears") else {
        return;
    };
    let args = format!(
        "lidar record --device xv11 --port {} --duration 20 --idle-timeout 1 --json --out {}",
        socat.b.display(),
        dir.join("v.bin").display()
    );
    let rec = Command::new(BIN)
        .args(args.split_whitespace())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let bytes = std::fs::read(capture("hand_in_box.bin")).unwrap();
    std::fs::write(&socat.a, &bytes[..20_000]).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let gone = Instant::now();
    drop(socat); // the port vanishes mid-stream
    let out = rec.wait_with_output().unwrap();
    assert!(
        gone.elapsed() < Duration::from_secs(4),
        "took {:?}",
        gone.elapsed()
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        assert_eq!(last_json(&out)["stopped_by_silence"], true);
        assert!(stderr.contains("recording ended early"), "{stderr}");
    } else {
        assert!(stderr.contains("read or write failed"), "{stderr}");
    }
}
