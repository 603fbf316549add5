//! `plumbline slam` end to end: on the bundled real excerpt (scored against its relations), on
//! a simulated survey (scored against the exact truth and the world's walls), and on inputs
//! that are wrong in the ways real logs are.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> serde_json::Value {
    let out = run(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    serde_json::from_str(stdout.lines().last().unwrap()).unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plumbline-slam-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn repo(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn the_excerpt_gets_a_pose_per_scan_a_map_and_a_graph_and_the_same_answer_twice() {
    let dir = temp_dir("excerpt");
    let (a, b, prefix) = (dir.join("a.txt"), dir.join("b.txt"), dir.join("map"));
    let log = repo("data/intel-excerpt.clf");
    let summary = ok(&["slam", &log, "--out", s(&a), "--map", s(&prefix), "--json"]);
    ok(&["slam", &log, "--out", s(&b), "--json"]);
    let first = std::fs::read_to_string(&a).unwrap();
    assert_eq!(
        first,
        std::fs::read_to_string(&b).unwrap(),
        "not deterministic"
    );
    let scans = summary["scans"].as_u64().unwrap() as usize;
    assert_eq!(first.lines().count(), scans);
    let eval = ok(&[
        "eval",
        s(&a),
        &repo("data/intel-excerpt.relations"),
        "--json",
    ]);
    let error = eval["trans_mean_m"].as_f64().unwrap();
    assert!(error < 0.025, "{eval}");
    // The map_server pair says where its own image is and how big a cell is.
    let yaml = std::fs::read_to_string(dir.join("map.yaml")).unwrap();
    assert!(
        yaml.contains("image: \"map.pgm\"") && yaml.contains("resolution: 0.05"),
        "{yaml}"
    );
    assert!(std::fs::read(dir.join("map.pgm"))
        .unwrap()
        .starts_with(b"P5"));
    assert!(std::fs::read(dir.join("map.png"))
        .unwrap()
        .starts_with(b"\x89PNG"));
    let g2o = std::fs::read_to_string(dir.join("map.g2o")).unwrap();
    let vertices = g2o.lines().filter(|l| l.starts_with("VERTEX_SE2")).count();
    assert_eq!(vertices as u64, summary["keyframes"].as_u64().unwrap());
    assert!(g2o.lines().filter(|l| l.starts_with("EDGE_SE2")).count() >= vertices - 1);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_map_prefix_in_a_missing_directory_fails_before_any_work() {
    let dir = temp_dir("prefix");
    let prefix = dir.join("no-such-dir").join("map");
    let traj = dir.join("t.txt");
    let out = run(&[
        "slam",
        &repo("data/intel-excerpt.clf"),
        "--out",
        s(&traj),
        "--map",
        s(&prefix),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("does not exist"), "{err}");
    assert!(
        !traj.exists(),
        "work was done before the prefix was checked"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The excerpt with its stamps and ranges rewritten line by line.
fn rewritten(dir: &Path, name: &str, edit: impl Fn(usize, &mut Vec<String>)) -> PathBuf {
    let text = std::fs::read_to_string(repo("data/intel-excerpt.clf")).unwrap();
    let mut out = String::new();
    let mut scan = 0;
    for line in text.lines() {
        let mut fields: Vec<String> = line.split_whitespace().map(str::to_owned).collect();
        if fields.first().map(String::as_str) == Some("FLASER") {
            edit(scan, &mut fields);
            scan += 1;
        }
        out += &fields.join(" ");
        out.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

fn poses(path: &Path) -> Vec<[f64; 4]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|f| f.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

#[test]
fn a_log_cut_off_mid_line_names_the_line_and_leaves_the_old_outputs_alone() {
    let dir = temp_dir("cut");
    let full = std::fs::read_to_string(repo("data/intel-excerpt.clf")).unwrap();
    // Cut in the middle of a scan line three quarters of the way through, as a recorder that
    // lost power leaves a file.
    let at = full[..full.len() * 3 / 4].rfind("FLASER").unwrap() + 40;
    let log = dir.join("cut.clf");
    std::fs::write(&log, &full[..at]).unwrap();
    let line = full[..at].lines().count();
    let traj = dir.join("t.txt");
    std::fs::write(&traj, "old\n").unwrap();
    let out = run(&[
        "slam",
        s(&log),
        "--out",
        s(&traj),
        "--map",
        s(&dir.join("m")),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("cut.clf:{line}")), "{err}");
    assert_eq!(std::fs::read_to_string(&traj).unwrap(), "old\n");
    assert!(!dir.join("m.pgm").exists());
    // With the bad line passed over, every scan before it is mapped.
    let summary = ok(&["slam", s(&log), "--skip-bad-lines", "--json"]);
    let scans_before = full[..at]
        .lines()
        .filter(|l| l.starts_with("FLASER "))
        .count()
        - 1;
    assert_eq!(summary["scans"].as_u64().unwrap() as usize, scans_before);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_blind_stretch_is_reported_as_lost_and_never_turns_into_nan() {
    let dir = temp_dir("blind");
    // 60 scans (about 12 s) where every beam reads the sensor's "no return".
    let log = rewritten(&dir, "blind.clf", |i, f| {
        if (200..260).contains(&i) {
            for r in &mut f[2..182] {
                *r = "81.83".into();
            }
        }
    });
    let traj = dir.join("t.txt");
    let summary = ok(&["slam", s(&log), "--out", s(&traj), "--json"]);
    assert!(summary["lost_s"].as_f64().unwrap() > 10.0, "{summary}");
    assert!(
        summary["predicted_scans"].as_u64().unwrap() >= 60,
        "{summary}"
    );
    let p = poses(&traj);
    assert!(p.iter().flatten().all(|v| v.is_finite()));
    // The predicted poses are marked in the file, so no consumer takes them for measurements.
    let text = std::fs::read_to_string(&traj).unwrap();
    assert!(
        text.lines().any(|l| l.starts_with("# lost ")),
        "no lost interval marked"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_jump_of_minutes_in_the_stamps_changes_nothing_but_the_stamps() {
    let dir = temp_dir("jump");
    let jump = |i: usize, f: &mut Vec<String>| {
        if i >= 300 {
            let n = f.len();
            for k in [n - 3, n - 1] {
                let t: f64 = f[k].parse().unwrap();
                f[k] = format!("{:.6}", t + 600.0);
            }
        }
    };
    let jumped = rewritten(&dir, "jump.clf", jump);
    let plain = rewritten(&dir, "plain.clf", |_, _| {});
    let (a, b) = (dir.join("a.txt"), dir.join("b.txt"));
    ok(&["slam", s(&plain), "--out", s(&a), "--json"]);
    ok(&["slam", s(&jumped), "--out", s(&b), "--json"]);
    let (pa, pb) = (poses(&a), poses(&b));
    assert_eq!(pa.len(), pb.len());
    for (x, y) in pa.iter().zip(&pb) {
        assert_eq!(x[1..], y[1..], "the motion estimate depends on the clock");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Flies the office survey (seed 7) with `lidar` into `dir`.
fn office_survey(dir: &Path, lidar: &str) {
    ok(&[
        "sim",
        "--world",
        "office",
        "--scenario",
        "survey",
        "--lidar",
        lidar,
        "--seed",
        "7",
        "--out",
        s(dir),
        "--json",
    ]);
}

#[test]
fn a_simulated_survey_with_a_long_range_lidar_closes_loops_and_maps_the_true_walls() {
    let dir = temp_dir("survey");
    office_survey(&dir, "utm30lx");
    let path = |n: &str| dir.join(n).to_str().unwrap().to_owned();
    let summary = ok(&[
        "slam",
        &path("scans.clf"),
        "--out",
        &path("slam.txt"),
        "--world",
        "office",
        "--truth",
        &path("truth.txt"),
        "--json",
    ]);
    let eval = ok(&[
        "eval",
        &path("slam.txt"),
        &path("truth.relations"),
        "--json",
    ]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        summary["loop_closures_accepted"].as_u64().unwrap() > 0,
        "{summary}"
    );
    assert!(eval["trans_mean_m"].as_f64().unwrap() < 0.01, "{eval}");
    // Occupied cells lie on the true walls: half a 5 cm cell is the floor of the metric.
    let map_error = summary["map_error_m"].as_f64().unwrap();
    assert!(map_error <= 0.05, "{summary}");
}

#[test]
fn a_slowly_spinning_lidar_named_with_lidar_is_de_skewed_and_maps_closer_to_the_walls() {
    let dir = temp_dir("deskew");
    office_survey(&dir, "xv11");
    let clf = dir.join("scans.clf");
    let truth = dir.join("truth.txt");
    let slam = |extra: &[&str]| {
        let mut args = vec!["slam", s(&clf), "--world", "office", "--truth", s(&truth)];
        args.extend_from_slice(extra);
        args.push("--json");
        ok(&args)["map_error_m"].as_f64().unwrap()
    };
    let (skewed, deskewed) = (slam(&[]), slam(&["--lidar", "xv11"]));
    let unknown = run(&["slam", s(&clf), "--lidar", "xv12"]);
    std::fs::remove_dir_all(&dir).ok();
    // The XV-11 takes 0.25 s per revolution: taken as a snapshot, the surveyed walls come out
    // twice as far from the true ones as they do de-skewed.
    assert!(
        deskewed < 0.1,
        "{deskewed} m de-skewed, {skewed} m as taken"
    );
    // (Naming the lidar also turns on the matcher's localizability check, which on this seed
    // costs the de-skewed map 0.081 -> 0.098 m while it lowers the ten-seed mean and worst.)
    assert!(
        deskewed < 0.7 * skewed,
        "{deskewed} m de-skewed, {skewed} m as taken"
    );
    assert!(!unknown.status.success());
    let message = String::from_utf8_lossy(&unknown.stderr);
    assert!(
        message.contains("--lidar xv12") && message.contains("xv11"),
        "{message}"
    );
}
