//! `plumbline slam` on the Intel benchmark log thinned to every 4th and every 8th scan (as
//! `scripts/slam.sh` thins it), lidar only: scans far apart must neither lose tracking nor pull
//! the map apart. Skipped with a printed reason when `../shared/data` is not there.
//!
//! The bound is the target's: at most twice the full-rate figure (0.018 m).

mod support;

use std::path::Path;
use support::{ok_json, shared_data};

/// The log with only every `k`-th laser line kept (the first among them), other lines as they are.
fn thinned(log: &Path, k: usize, out: &Path) {
    let text = std::fs::read_to_string(log).unwrap();
    let mut scans = 0;
    let kept: Vec<&str> = text
        .lines()
        .filter(|line| {
            if !line.starts_with("FLASER") {
                return true;
            }
            scans += 1;
            (scans - 1) % k == 0
        })
        .collect();
    std::fs::write(out, kept.join("\n") + "\n").unwrap();
}

#[test]
fn intel_thinned_to_every_4th_and_8th_scan_stays_within_twice_the_full_rate_error() {
    let Some(d) = shared_data() else { return };
    let dir = std::env::temp_dir().join(format!("plumbline-thinned-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for k in [4, 8] {
        let log = dir.join(format!("intel-every{k}.clf"));
        let traj = dir.join(format!("intel-every{k}.txt"));
        thinned(&d.join("intel-lab/intel-first5505.derived.clf"), k, &log);
        let (log, traj) = (log.to_str().unwrap(), traj.to_str().unwrap());
        let summary = ok_json(&["slam", log, "--out", traj, "--json"]);
        let relations = d.join("intel-lab/intel.relations");
        let eval = ok_json(&["eval", traj, relations.to_str().unwrap(), "--json"]);
        println!("every {k}th: {summary}\n{eval}");
        // A scan or two may be bridged by prediction (Intel's stamps bunch, so two scans far
        // apart can carry stamps 0.1 s apart and a good match looks implausibly fast), but
        // tracking is not lost for longer.
        let (predicted, scans) = (
            summary["predicted_scans"].as_u64().unwrap(),
            summary["scans"].as_u64().unwrap(),
        );
        assert!(predicted * 100 <= scans, "{summary}");
        assert!(eval["matched"].as_u64().unwrap() > 0, "{eval}");
        let error = eval["trans_mean_m"].as_f64().unwrap();
        assert!(error <= 0.036, "every {k}th scan: {error} m ({eval})");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `(stamp, x, y)` of every pose of a trajectory file.
fn positions(path: &Path) -> Vec<(String, f64, f64)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (
                f[0].to_string(),
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
            )
        })
        .collect()
}

/// The largest distance between `thin`'s positions and `full`'s at the same stamps once the
/// rigid motion that best lays one on the other (least squares) is taken out, m.
fn largest_departure(full: &Path, thin: &Path) -> f64 {
    let full = positions(full);
    // Full-rate x, y, then thinned x, y, at each common stamp.
    let pairs: Vec<[f64; 4]> = positions(thin)
        .into_iter()
        .filter_map(|(t, x, y)| {
            full.iter()
                .find(|(s, _, _)| *s == t)
                .map(|&(_, fx, fy)| [fx, fy, x, y])
        })
        .collect();
    assert!(pairs.len() > 10, "too few common stamps: {}", pairs.len());
    let mean = |i: usize| pairs.iter().map(|p| p[i]).sum::<f64>() / pairs.len() as f64;
    let (ax, ay, bx, by) = (mean(0), mean(1), mean(2), mean(3));
    let (mut dot, mut cross) = (0.0, 0.0);
    for [fx, fy, x, y] in &pairs {
        let (u, v, p, q) = (x - bx, y - by, fx - ax, fy - ay);
        dot += u * p + v * q;
        cross += u * q - v * p;
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    pairs
        .iter()
        .map(|[fx, fy, x, y]| {
            let (u, v) = (x - bx, y - by);
            (c * u - s * v + ax - fx).hypot(s * u + c * v + ay - fy)
        })
        .fold(0.0, f64::max)
}

#[test]
fn mit_thinned_to_every_8th_scan_reports_where_its_path_leaves_the_full_rate_one() {
    let Some(d) = shared_data() else { return };
    let dir = std::env::temp_dir().join(format!("plumbline-mit-thinned-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = d.join("mit-csail/mit-csail.clf");
    let (full, thin, thin_log) = (
        dir.join("full.txt"),
        dir.join("every8.txt"),
        dir.join("every8.clf"),
    );
    let full_summary = ok_json(&[
        "slam",
        log.to_str().unwrap(),
        "--out",
        full.to_str().unwrap(),
        "--json",
    ]);
    // At full rate every wide search the map contradicts would be a false alarm.
    assert_eq!(
        full_summary["relocalizations_unconfirmed"], 0,
        "{full_summary}"
    );
    thinned(&log, 8, &thin_log);
    let summary = ok_json(&[
        "slam",
        thin_log.to_str().unwrap(),
        "--out",
        thin.to_str().unwrap(),
        "--json",
    ]);
    let departure = largest_departure(&full, &thin);
    println!("every 8th: {departure:.2} m at most from the full-rate path\n{summary}");
    // Turns of up to 170° between scans: the guard finds a pose for every scan, the local
    // map standing in when the keyframe shares too little of the view…
    assert_eq!(summary["relocalizations_failed"], 0, "{summary}");
    // …and a path that leaves the full-rate one does not do so silently.
    if departure > 1.0 {
        let reported = summary["relocalizations_unconfirmed"].as_u64().unwrap()
            + summary["lost_intervals"].as_u64().unwrap();
        assert!(
            reported > 0,
            "{departure} m off, nothing reported: {summary}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
