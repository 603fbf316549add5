//! `plumbline companion` end to end: recorded lidar data through the SLAM into a UDP socket on
//! loopback, every datagram decoded as MAVLink 2 (the `mavlink` crate here; pymavlink in
//! `tests/mavlink/companion_client.py`), the autopilot's estimate read back as the SLAM's motion
//! guess (pymavlink as the autopilot, `tests/mavlink/companion_autopilot.py`), and bad input as
//! clear errors.

mod support;

use mavlink::dialects::common::{
    MavDistanceSensor, MavEstimatorType, MavFrame, MavMessage, MavType, OBSTACLE_DISTANCE_DATA,
    ODOMETRY_DATA,
};
use mavlink::{MavlinkReader, MavlinkVersion};
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;
use support::{capture, excerpt, last_json, p, run, scratch, socat_pair, stderr, Socat, BIN, REPO};

/// A loopback socket whose buffer holds a whole replay: the companion sends a log's poses as
/// fast as it decodes them, and on a loaded machine this test may not be scheduled to drain
/// the default 208 KB before the kernel drops datagrams (the kernel caps the size at its
/// `rmem_max`).
fn receiver() -> UdpSocket {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket2::SockRef::from(&socket)
        .set_recv_buffer_size(4 << 20)
        .unwrap();
    socket
}

/// What one run sent, decoded, with its summary.
struct Received {
    summary: serde_json::Value,
    heartbeats: Vec<MavType>,
    odometry: Vec<ODOMETRY_DATA>,
    obstacles: Vec<OBSTACLE_DISTANCE_DATA>,
    other: usize,
}

/// Runs the companion with `input` sending to a fresh loopback socket, and decodes every
/// datagram that arrived while it ran.
fn companion(input: &[&str]) -> Received {
    let socket = receiver();
    socket
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let to = format!("udpout:{}", socket.local_addr().unwrap());
    let mut args: Vec<&str> = vec!["companion", "--mavlink", &to, "--json"];
    args.extend(input);
    let mut child = Command::new(BIN)
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut datagrams = Vec::new();
    let mut buf = [0u8; 2048];
    // Read while it runs, then until the socket has been quiet for a while.
    let mut quiet = 0;
    while quiet < 3 {
        match socket.recv(&mut buf) {
            Ok(n) => {
                datagrams.push(buf[..n].to_vec());
                quiet = 0;
            }
            Err(_) if child.try_wait().unwrap().is_some() => quiet += 1,
            Err(_) => {}
        }
    }
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let mut r = Received {
        summary: last_json(&out),
        heartbeats: Vec::new(),
        odometry: Vec::new(),
        obstacles: Vec::new(),
        other: 0,
    };
    for d in &datagrams {
        let mut reader = MavlinkReader::new(d.as_slice());
        let (_, msg) = reader
            .read_message::<MavMessage>(MavlinkVersion::V2)
            .unwrap_or_else(|e| panic!("not one MAVLink 2 frame ({e:?}): {d:02x?}"));
        match msg {
            MavMessage::HEARTBEAT(h) => r.heartbeats.push(h.mavtype),
            MavMessage::ODOMETRY(o) => r.odometry.push(o),
            MavMessage::OBSTACLE_DISTANCE(o) => r.obstacles.push(o),
            _ => r.other += 1,
        }
    }
    r
}

fn yaw_frd(o: &ODOMETRY_DATA) -> f32 {
    let [w, x, y, z] = o.q;
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

#[test]
fn the_capture_arrives_as_one_odometry_and_one_obstacle_message_per_revolution() {
    let r = companion(&["--lidar", "xv11", "--replay", p(&capture())]);
    let s = &r.summary;
    let scans = s["scans"].as_u64().unwrap() as usize;
    assert_eq!(scans, 161, "{s}");
    assert_eq!(
        (r.odometry.len(), r.obstacles.len(), r.other),
        (scans, scans, 0)
    );
    assert_eq!(s["odometry_sent"], scans);
    // The hand covers the lidar for a while: those revolutions are empty and sent as lost.
    let lost = r.odometry.iter().filter(|o| o.quality == -1).count();
    assert_eq!(lost as u64, s["lost_scans"].as_u64().unwrap());
    assert!(s["empty_scans"].as_u64().unwrap() > 0 && lost > 0, "{s}");
    for o in &r.odometry {
        assert_eq!(o.frame_id, MavFrame::MAV_FRAME_LOCAL_FRD);
        assert_eq!(o.child_frame_id, MavFrame::MAV_FRAME_BODY_FRD);
        assert_eq!(
            o.estimator_type,
            MavEstimatorType::MAV_ESTIMATOR_TYPE_VISION
        );
        assert!((-1..=100).contains(&o.quality));
        let norm: f32 = o.q.iter().map(|v| v * v).sum();
        assert!((norm - 1.0).abs() < 1e-5 && o.q[1] == 0.0 && o.q[2] == 0.0);
        // x, y and yaw variances positive; what a 2-D lidar cannot see (height, roll, pitch)
        // finite (an autopilot drops a pose with a NaN) and no better than what it sees.
        let c = &o.pose_covariance;
        assert!(c[0] > 0.0 && c[6] > 0.0 && c[20] > 0.0, "{c:?}");
        assert!(o.z.is_finite() && c.iter().all(|v| v.is_finite()), "{c:?}");
        assert!(
            c[11] == c[0].max(c[6]) && c[15] == c[20] && c[18] == c[20],
            "{c:?}"
        );
        assert!(o.velocity_covariance[0].is_nan() && o.vx.is_nan());
        if o.quality == -1 {
            assert!(c[0] >= 100.0, "a lost pose claims {} m^2", c[0]);
        }
    }
    // The reset counter only goes up, and ends where the summary says.
    let resets: Vec<u8> = r.odometry.iter().map(|o| o.reset_counter).collect();
    assert!(resets.windows(2).all(|w| w[1] >= w[0]), "{resets:?}");
    assert_eq!(s["reset_counter"], u64::from(*resets.last().unwrap()));
    assert!(s["relocalizations"].as_u64().unwrap() >= u64::from(*resets.last().unwrap()));
    // Heartbeats once a second of capture time, as a companion computer.
    let span_s = (r.odometry[scans - 1].time_usec - r.odometry[0].time_usec) as f64 * 1e-6;
    assert!(r
        .heartbeats
        .iter()
        .all(|t| *t == MavType::MAV_TYPE_ONBOARD_CONTROLLER));
    let beats = r.heartbeats.len() as f64;
    assert!(
        (beats - span_s).abs() <= 1.5,
        "{beats} heartbeats in {span_s} s"
    );
    for (o, odo) in r.obstacles.iter().zip(&r.odometry) {
        assert_eq!(o.frame, MavFrame::MAV_FRAME_BODY_FRD);
        assert_eq!(o.sensor_type, MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER);
        assert_eq!((o.increment, o.increment_f, o.angle_offset), (5, 5.0, 0.0));
        let known: Vec<u16> = o
            .distances
            .iter()
            .copied()
            .filter(|d| *d != u16::MAX)
            .collect();
        // A sector's nearest return, or max_distance + 1 for "nothing in range".
        assert!(known
            .iter()
            .all(|d| (o.min_distance..=o.max_distance + 1).contains(d)));
        // An empty revolution knows no sector; a matched one knows some.
        if odo.quality > 0 {
            assert!(!known.is_empty());
        }
    }
}

#[test]
fn a_carmen_log_replayed_gives_a_trajectory_that_scores_against_its_relations() {
    let log = excerpt();
    let relations = Path::new(REPO).join("data/intel-excerpt.relations");
    let r = companion(&["--replay-log", p(&log)]);
    assert_eq!(r.odometry.len(), 597);
    assert!(r
        .odometry
        .iter()
        .all(|o| o.quality > 0 || o.time_usec == r.odometry[0].time_usec));
    // Back from the wire's frames (y and heading negated) into a trajectory file.
    let text: String = r
        .odometry
        .iter()
        .map(|o| {
            let t = o.time_usec as f64 * 1e-6;
            format!("{t:.6} {} {} {}\n", o.x, -o.y, -yaw_frd(o))
        })
        .collect();
    let dir = scratch("companion-intel");
    let traj = dir.join("traj.txt");
    std::fs::write(&traj, text).unwrap();
    let eval = run(&["eval", p(&traj), p(&relations), "--json"]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    let e = last_json(&eval);
    assert_eq!(e["matched"], e["relations"], "{e}");
    // `plumbline slam` scores 0.015 m and 0.12 deg on this excerpt; the online poses the
    // autopilot gets are as good.
    assert!(e["trans_mean_m"].as_f64().unwrap() < 0.03, "{e}");
    assert!(e["rot_mean_deg"].as_f64().unwrap() < 0.5, "{e}");
}

#[test]
fn bad_input_is_a_clear_error() {
    let dir = scratch("companion-bad");
    let garbage = dir.join("garbage.bin");
    let bytes: Vec<u8> = (0..5000u32).map(|i| (i * 7 % 251) as u8 & 0x7F).collect();
    std::fs::write(&garbage, bytes).unwrap();
    let empty_log = dir.join("empty.clf");
    std::fs::write(&empty_log, "# nothing here\n").unwrap();
    let to = "udpout:127.0.0.1:9";
    for (args, says) in [
        (
            vec!["--lidar", "xv11", "--replay", p(&garbage)],
            "no valid xv11 frame",
        ),
        (vec!["--replay", p(&capture())], "--replay needs --lidar"),
        (
            vec!["--replay-log", p(&empty_log)],
            "no FLASER or ROBOTLASER1",
        ),
        (
            vec!["--lidar", "xv11", "--port", "/dev/plumbline-no-such-port"],
            "/dev/plumbline-no-such-port: cannot open",
        ),
        (
            vec!["--replay-log", p(&excerpt()), "--port", "/dev/x"],
            "cannot be used with",
        ),
    ] {
        let mut all = vec!["companion", "--mavlink", to];
        all.extend(&args);
        let out = run(&all);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
    }
    let out = run(&["companion", "--mavlink", "udp:1.2.3.4", "--replay-log", "x"]);
    assert!(
        stderr(&out).contains("udpout:HOST:PORT"),
        "{}",
        stderr(&out)
    );
}

/// Runs the companion on the far end of a virtual serial pair; `feed` gets the pair half a
/// second after the start, writes the lidar's bytes into its near end and hands it back to stay
/// plugged in until the run ends, or drops it (unplugs it). `None`, with the reason printed,
/// where socat cannot run.
fn live(
    test: &str,
    idle_timeout_s: &str,
    feed: impl FnOnce(Socat) -> Option<Socat>,
) -> Option<Output> {
    let dir = scratch(test);
    let socat = socat_pair(&dir, test)?;
    let socket = receiver();
    let to = format!("udpout:{}", socket.local_addr().unwrap());
    let child = Command::new(BIN)
        .args(["companion", "--lidar", "xv11", "--port", p(&socat.b)])
        .args(["--idle-timeout", idle_timeout_s, "--mavlink", &to, "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let _plugged = feed(socat);
    Some(child.wait_with_output().unwrap())
}

#[test]
fn a_lidar_port_that_falls_silent_ends_the_run_with_what_it_sent() {
    let Some(out) = live("companion-silent", "1", |socat| {
        std::fs::write(&socat.a, std::fs::read(capture()).unwrap()).unwrap();
        Some(socat)
    }) else {
        return;
    };
    assert!(out.status.success(), "{}", stderr(&out));
    let s = last_json(&out);
    assert_eq!(s["stopped_by_silence"], true, "{s}");
    assert!(s["scans"].as_u64().unwrap() > 100, "{s}");
    assert_eq!(s["odometry_sent"], s["scans"]);
}

#[test]
fn a_lidar_port_that_vanishes_mid_run_keeps_what_was_sent_and_fails() {
    let Some(out) = live("companion-vanish", "5", |socat| {
        let bytes = std::fs::read(capture()).unwrap();
        std::fs::write(&socat.a, &bytes[..bytes.len() / 2]).unwrap();
        std::thread::sleep(Duration::from_millis(500));
        None // the adapter is unplugged
    }) else {
        return;
    };
    assert!(
        !out.status.success(),
        "a vanished port ended the run as if asked"
    );
    assert!(stderr(&out).contains("device gone"), "{}", stderr(&out));
    let s = last_json(&out);
    assert!(s["failure"].is_string(), "{s}");
    assert!(s["scans"].as_u64().unwrap() > 50, "{s}");
    assert_eq!(s["odometry_sent"], s["scans"]);
}

/// Runs a pymavlink script from the project's venv with `args`; fails the test on its failure.
fn run_pymavlink_script(script: &str, args: &[&std::ffi::OsStr]) {
    let python = Path::new(REPO).join(".venv/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run scripts/setup.sh (it makes the venv with pymavlink)",
        python.display()
    );
    let out = Command::new(&python)
        .arg(Path::new(REPO).join(script))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        stderr(&out)
    );
}

#[test]
fn pymavlink_as_the_autopilot_accepts_every_message() {
    let capture = capture();
    run_pymavlink_script(
        "tests/mavlink/companion_client.py",
        &[BIN.as_ref(), capture.as_ref()],
    );
}

/// Runs `tests/mavlink/companion_autopilot.py CASE`: pymavlink plays an autopilot that streams
/// its estimate back while the companion replays a corridor whose posts repeat, so a
/// revolution's motion is ambiguous to the scans alone (see the script).
fn autopilot_case(case: &str) {
    let dir = scratch(&format!("companion-autopilot-{case}"));
    run_pymavlink_script(
        "tests/mavlink/companion_autopilot.py",
        &[BIN.as_ref(), dir.as_ref(), case.as_ref()],
    );
}

#[test]
fn the_autopilots_position_and_attitude_guess_the_motion_the_scans_cannot_tell() {
    autopilot_case("position");
}

#[test]
fn the_autopilots_odometry_guesses_the_motion_the_scans_cannot_tell() {
    autopilot_case("odometry");
}

#[test]
fn without_the_autopilots_estimate_the_ambiguous_corridor_is_read_backwards() {
    autopilot_case("silent");
}

#[test]
fn a_silent_nan_failed_or_rebooted_autopilot_guesses_nothing_across_the_fault() {
    autopilot_case("hostile");
}
