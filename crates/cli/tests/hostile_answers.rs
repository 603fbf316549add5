//! Hostile inputs that used to give a wrong answer with exit 0: each case must now be an error
//! naming what is wrong, or a loud, documented degraded mode. Run against the real binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_plumbline");
const REPO_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data");

fn tmp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "plumbline-hostile-answers-{name}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn run<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn last_json(out: &Output) -> serde_json::Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap()
}

// ---- eval: no perfect score for nothing ----

const TRAJ: &str = "1.0 0 0 0\n2.0 1 0 0\n3.0 2 0 0\n4.0 3 0 0\n";

#[test]
fn eval_with_an_empty_relations_file_is_an_error() {
    let dir = tmp_dir("eval-empty");
    let traj = write(&dir, "t.traj", TRAJ);
    let rel = write(&dir, "empty.relations", "");
    let out = eval(&traj, &rel);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("no relation"), "{}", stderr(&out));
}

fn eval(traj: &Path, rel: &Path) -> Output {
    run(&[
        "eval".as_ref(),
        traj.as_os_str(),
        rel.as_os_str(),
        "--json".as_ref(),
    ])
}

#[test]
fn eval_where_no_stamp_matches_is_an_error() {
    let dir = tmp_dir("eval-nomatch");
    let traj = write(&dir, "t.traj", TRAJ);
    let rel = write(
        &dir,
        "r.relations",
        "11.0 12.0 1 0 0 0 0 0\n12.0 13.0 1 0 0 0 0 0\n",
    );
    let out = eval(&traj, &rel);
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(e.contains("none of the 2 relations"), "{e}");
    assert!(out.stdout.is_empty(), "no summary with a score");
}

#[test]
fn eval_with_a_low_match_ratio_warns_loudly_and_says_so_in_the_json() {
    let dir = tmp_dir("eval-low");
    let traj = write(&dir, "t.traj", TRAJ);
    let rel = write(
        &dir,
        "r.relations",
        "1.0 2.0 1 0 0 0 0 0\n11.0 12.0 1 0 0 0 0 0\n12.0 13.0 1 0 0 0 0 0\n",
    );
    let out = eval(&traj, &rel);
    assert!(out.status.success());
    assert!(
        stderr(&out).contains("WARNING: only 1 of 3"),
        "{}",
        stderr(&out)
    );
    let j = last_json(&out);
    assert_eq!(j["matched"], 1);
    assert_eq!(j["low_match_ratio"], true);
    assert!((j["match_ratio"].as_f64().unwrap() - 1.0 / 3.0).abs() < 1e-12);

    let good = write(
        &dir,
        "g.relations",
        "1.0 2.0 1 0 0 0 0 0\n2.0 3.0 1 0 0 0 0 0\n",
    );
    let j = last_json(&eval(&traj, &good));
    assert_eq!(j["low_match_ratio"], false);
    assert_eq!(j["match_ratio"], 1.0);
}

// ---- CARMEN records parse exactly ----

const FLASER_OK: &str = "FLASER 3 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n";

#[test]
fn a_beam_count_that_disagrees_with_the_line_is_an_error_naming_file_line_and_field() {
    let dir = tmp_dir("carmen-count");
    let cases = [
        ("flaser-more", "FLASER 2 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n"),
        ("flaser-less", "FLASER 4 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5\n"),
        ("flaser-trailing", "FLASER 3 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 100.25 host 1.5 9\n"),
        ("robotlaser-remissions", "ROBOTLASER1 0 -2.094395 4.188790 0.006136 5.600 0.010 0 4 1.0 5.6 2.5 0.0 1 0.1 0.2 0 0 0 1.5 2.5 0.3 0 0 0 0 0 11.5 host 0.5\n"),
        ("odom-trailing", "ODOM 1 2 0.5 0 0 0 99.0 h 99.0 3\n"),
    ];
    for (name, bad) in cases {
        let log = write(
            &dir,
            &format!("{name}.clf"),
            &format!("{FLASER_OK}{FLASER_OK}{bad}{FLASER_OK}"),
        );
        let out = run(&["odometry".as_ref(), log.as_os_str()]);
        assert!(!out.status.success(), "{name} accepted");
        let e = stderr(&out);
        assert!(e.contains(&format!("{name}.clf:3:")), "{name}: {e}");
        assert!(e.contains("field"), "{name}: {e}");
    }
}

// ---- numeric options: a documented range, checked at parse time ----

/// Every numeric option of every subcommand (the subcommand, the other arguments it needs, the
/// option) with the range its help text documents.
const NUMERIC_OPTIONS: &[(&[&str], &[&str], &str, &str)] = &[
    (&["odometry"], &["x.clf"], "--keyframe-distance", "(0, 10]"),
    (
        &["odometry"],
        &["x.clf"],
        "--keyframe-angle-deg",
        "(0, 180]",
    ),
    (&["odometry"], &["x.clf"], "--map-cell", "[0.01, 10]"),
    (&["odometry"], &["x.clf"], "--map-size", "(0, 10000]"),
    (
        &["odometry"],
        &["x.clf"],
        "--map-matcher-weight",
        "[0, 100]",
    ),
    (&["odometry"], &["x.clf"], "--fov-deg", "(0, 360]"),
    (&["odometry"], &["x.clf"], "--max-range", "(0, 1000]"),
    (&["eval"], &["a", "b"], "--tolerance", "[0, 1]"),
    (&["sim"], &[], "--duration", "(0, 86400]"),
    (&["sim"], &[], "--physics-hz", "[100, 20000]"),
    (&["sim"], &[], "--fov-deg", "(0, 360]"),
    (&["sim"], &[], "--max-range", "(0, 1000]"),
    (
        &["lidar", "decode"],
        &["--device", "xv11", "x.bin"],
        "--baud",
        "[1200, 4000000]",
    ),
    (&["lidar", "record"], RECORD, "--baud", "[1200, 4000000]"),
    (&["lidar", "record"], RECORD, "--duration", "(0, 86400]"),
    (&["lidar", "record"], RECORD, "--idle-timeout", "(0, 3600]"),
];

const RECORD: &[&str] = &[
    "--device",
    "xv11",
    "--port",
    "/nonexistent",
    "--out",
    "x.bin",
];

#[test]
fn every_numeric_option_refuses_nan_infinity_and_out_of_range_values_at_parse_time() {
    for (command, others, option, range) in NUMERIC_OPTIONS {
        let zero_is_valid = range.starts_with("[0,");
        for bad in ["NaN", "inf", "-inf", "-1", "1e30", "0", "nonsense", ""] {
            if bad == "0" && zero_is_valid {
                continue;
            }
            let mut args: Vec<String> = command
                .iter()
                .chain(*others)
                .map(|a| a.to_string())
                .collect();
            args.push(format!("{option}={bad}"));
            let out = run(&args);
            assert_eq!(out.status.code(), Some(2), "{args:?} accepted");
            let e = stderr(&out);
            assert!(e.contains(option) && e.contains(range), "{args:?}: {e}");
        }
        // The range is documented where the user looks for it.
        let mut help = command.to_vec();
        help.push("--help");
        let text = String::from_utf8_lossy(&run(&help).stdout).into_owned();
        let doc = text
            .split(&format!("{option} <"))
            .nth(1)
            .unwrap_or_else(|| panic!("{help:?} has no {option}"));
        let doc = doc.split("\n      -").next().unwrap();
        assert!(
            doc.contains(&format!("Valid range: {range}")),
            "{help:?} {option}: {doc}"
        );
    }
}

#[test]
fn baud_zero_no_longer_shifts_stamps_it_is_refused() {
    let capture = Path::new(REPO_DATA).join("captures/neato-xv11/hand_in_box.bin");
    let out = run(&[
        "lidar".as_ref(),
        "decode".as_ref(),
        "--device".as_ref(),
        "xv11".as_ref(),
        capture.as_os_str(),
        "--baud".as_ref(),
        "0".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(2));
}

// ---- a lidar that stops returning is not a vehicle that keeps turning ----

/// Sum of |heading change| over consecutive rows of a trajectory, from row `from` on.
fn turned(rows: &[(String, f64)], from: usize) -> f64 {
    rows[from..]
        .windows(2)
        .map(|w| {
            let d = (w[1].1 - w[0].1).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d)
        })
        .sum()
}

#[test]
fn a_capture_that_spins_down_is_marked_lost_not_spun_for_turns() {
    let dir = tmp_dir("spin-down");
    let capture = Path::new(REPO_DATA).join("captures/neato-xv11/hand_in_box.bin");
    let log = dir.join("hib.log");
    let traj = dir.join("hib.traj");
    let decode = run(&[
        "lidar".as_ref(),
        "decode".as_ref(),
        "--device".as_ref(),
        "xv11".as_ref(),
        capture.as_os_str(),
        "--out".as_ref(),
        log.as_os_str(),
    ]);
    assert!(decode.status.success(), "{}", stderr(&decode));
    let out = run(&[
        "odometry".as_ref(),
        log.as_os_str(),
        "--out".as_ref(),
        traj.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let j = last_json(&out);
    let lost_scans = j["lost_scans"].as_u64().unwrap();
    assert!(lost_scans >= 30, "{j}");
    assert!(j["lost_s"].as_f64().unwrap() > 4.0, "{j}");
    assert!(
        stderr(&out).contains("no measurement for"),
        "{}",
        stderr(&out)
    );

    let text = std::fs::read_to_string(&traj).unwrap();
    let lost_lines: Vec<&str> = text.lines().filter(|l| l.starts_with("# lost ")).collect();
    let marked: u64 = lost_lines
        .iter()
        .map(|l| l.split_whitespace().nth(4).unwrap().parse::<u64>().unwrap())
        .sum();
    assert_eq!(marked, lost_scans, "{lost_lines:?}");
    let rows: Vec<(String, f64)> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f[0].to_string(), f[3].parse().unwrap())
        })
        .collect();
    // The last run of lost poses: however long it lasts, it turns less than the prediction bound
    // (twice the last measured motion) allows, and it ends at rest.
    let last = lost_lines.last().unwrap();
    let first_lost = last.split_whitespace().nth(2).unwrap();
    let k = rows.iter().position(|r| r.0 == first_lost).unwrap();
    let biggest_measured_step = (1..k)
        .map(|i| turned(&rows[i - 1..=i], 0))
        .fold(0.0, f64::max);
    let lost_turn = turned(&rows, k - 1);
    assert!(
        lost_turn <= 2.0 * biggest_measured_step + 1e-3,
        "turned {lost_turn} rad while lost (largest measured step {biggest_measured_step})"
    );
    assert!(
        turned(&rows[rows.len() - 5..], 0) < 1e-3,
        "still turning at the end"
    );

    // `eval` reads the file and does not score relations on lost poses.
    let measured = &rows[k - 1].0;
    let relations = write(
        &dir,
        "r.relations",
        &format!(
            "{} {measured} 0 0 0 0 0 0\n{measured} {} 0 0 0 0 0 0\n",
            rows[0].0,
            rows.last().unwrap().0
        ),
    );
    let e = eval(&traj, &relations);
    assert!(e.status.success(), "{}", stderr(&e));
    let s = last_json(&e);
    assert_eq!(
        (s["matched"].as_u64(), s["lost_relations"].as_u64()),
        (Some(1), Some(1)),
        "{s}"
    );
}

// ---- decoders refuse what the device cannot have sent ----

fn decode(device: &str, capture: &Path) -> Output {
    run(&[
        "lidar".as_ref(),
        "decode".as_ref(),
        "--device".as_ref(),
        device.as_ref(),
        capture.as_os_str(),
        "--json".as_ref(),
    ])
}

/// A fixed xorshift stream: reproducible bytes with no structure.
fn noise(len: usize, seed: u64) -> Vec<u8> {
    let mut x = seed | 1;
    (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect()
}

/// RPLIDAR standard-scan bytes: the response descriptor, then `turns` revolutions of one node a
/// degree clockwise, 2 m away.
fn rplidar_capture(turns: usize) -> Vec<u8> {
    let mut out = vec![0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
    for _ in 0..turns {
        for deg in 0..360u16 {
            let start = u8::from(deg == 0);
            out.push(47 << 2 | (1 - start) << 1 | start);
            out.extend(((deg * 64) << 1 | 1).to_le_bytes());
            out.extend(8000u16.to_le_bytes());
        }
    }
    out
}

#[test]
fn random_bytes_and_an_xv11_capture_are_not_an_rplidar() {
    let dir = tmp_dir("rplidar-foreign");
    let random = dir.join("random.bin");
    std::fs::write(&random, noise(1 << 20, 7)).unwrap();
    let xv11 = Path::new(REPO_DATA).join("captures/neato-xv11/hand_in_box.bin");
    for capture in [random, xv11] {
        let out = decode("rplidar", &capture);
        assert!(!out.status.success(), "{capture:?} decoded as an RPLIDAR");
        let e = stderr(&out);
        assert!(
            e.contains("do not look like rplidar data: 0 of") && e.contains("is --device right?"),
            "{e}"
        );
    }
}

#[test]
fn a_real_looking_rplidar_stream_still_decodes_and_counts_what_it_refused() {
    let dir = tmp_dir("rplidar-good");
    let good = dir.join("good.bin");
    // Noise before the good turns (a capture started mid-glitch): refused and counted, and the
    // good turns are kept.
    let mut bytes = noise(2000, 3);
    bytes.extend(rplidar_capture(3));
    std::fs::write(&good, bytes).unwrap();
    let out = decode("rplidar", &good);
    assert!(out.status.success(), "{}", stderr(&out));
    let j = last_json(&out);
    assert_eq!(j["revolutions"], 3, "{j}");
    assert!(j["implausible_revolutions"].as_u64().unwrap() > 0, "{j}");
    let rpm = j["rpm_median"].as_f64().unwrap();
    assert!((rpm - 60.0 / (360.0 * 0.0005)).abs() < 1.0, "{j}");
}

/// A SCIP line: payload and its sum character (the low 6 bits of the byte sum, plus 0x30).
fn scip_line(payload: &[u8]) -> Vec<u8> {
    let sum = payload.iter().map(|&b| u32::from(b)).sum::<u32>();
    let mut line = payload.to_vec();
    line.push((sum & 0x3F) as u8 + 0x30);
    line.push(b'\n');
    line
}

#[test]
fn an_urg_reply_for_steps_the_sensor_does_not_have_is_refused() {
    let dir = tmp_dir("urg-steps");
    // GD from step 760 to 780, three characters a value: the URG-04LX ends at step 768.
    let mut reply = b"GD0760078000\n".to_vec();
    reply.extend(scip_line(b"00"));
    reply.extend(scip_line(b"0000"));
    let data: Vec<u8> = (0..21).flat_map(|_| *b"0Fh").collect();
    reply.extend(scip_line(&data));
    reply.push(b'\n');
    let capture = write(&dir, "urg.bin", "");
    std::fs::write(&capture, &reply).unwrap();
    let out = decode("urg", &capture);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("0 of 1 revolutions plausible"),
        "{}",
        stderr(&out)
    );
}

// ---- worlds are validated before flying, rasters are bounded ----

const ROOM: &str = "outline 0 0 6 0 6 4 0 4\n";

fn sim_world(world: &Path) -> Output {
    run(&[
        "sim".as_ref(),
        "--world".as_ref(),
        world.as_os_str(),
        "--scenario".as_ref(),
        "hold".as_ref(),
        "--duration".as_ref(),
        "1".as_ref(),
        "--json".as_ref(),
    ])
}

#[test]
fn a_world_that_cannot_be_flown_is_refused_with_its_line() {
    let dir = tmp_dir("worlds");
    let cases = [
        (
            "outside",
            format!("{ROOM}start 10 2 0\n"),
            ":2",
            "not enclosed",
        ),
        (
            "far",
            format!("{ROOM}start 1e30 2 0\n"),
            ":2",
            "from the origin",
        ),
        (
            "far-wall",
            format!("start 3 2 0\n{ROOM}wall 0 0 -1e7 0\n"),
            ":3",
            "from the origin",
        ),
        (
            "twice",
            format!("start 3 2 0\n{ROOM}start 2 2 0\n"),
            ":3",
            "line 1",
        ),
        (
            "two-ceilings",
            format!("ceiling 3\nstart 3 2 0\n{ROOM}ceiling 2.5\n"),
            ":4",
            "line 1",
        ),
        (
            "waypoint-outside",
            format!("start 3 2 0\n{ROOM}path 1 1 5 3 9 9\n"),
            ":3",
            "waypoint 3",
        ),
    ];
    for (name, text, line, why) in cases {
        let path = write(&dir, &format!("{name}.world"), &text);
        let out = sim_world(&path);
        assert!(!out.status.success(), "{name} flown");
        let e = stderr(&out);
        assert!(
            e.contains(&format!("{name}.world")) && e.contains(why),
            "{name}: {e}"
        );
        assert!(e.contains(&format!("line {}", &line[1..])), "{name}: {e}");
    }
    // The same room with its start inside flies.
    let good = write(&dir, "good.world", &format!("{ROOM}start 3 2 0\n"));
    let out = sim_world(&good);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn rasterizing_a_log_with_an_absurd_pose_is_refused_with_its_line() {
    let dir = tmp_dir("rasterize");
    let scan = |x: &str| {
        let ranges = vec!["2.0"; 181].join(" ");
        format!("FLASER 181 {ranges} {x} 0 0 {x} 0 0 10.5 host 10.5\n")
    };
    for far in ["1e30", "1e7"] {
        let text = format!("{}{}{}{}", scan("0"), scan("0.1"), scan(far), scan("0.2"));
        let log = write(&dir, &format!("far-{far}.clf"), &text);
        let out = run(&[
            "sim".as_ref(),
            "--rasterize".as_ref(),
            log.as_os_str(),
            "--out".as_ref(),
            dir.join(format!("out-{far}")).as_os_str(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{far}: {}", stderr(&out));
        let e = stderr(&out);
        assert!(e.contains(&format!("far-{far}.clf:3:")), "{far}: {e}");
        assert!(e.contains("more than the"), "{far}: {e}");
    }
}
