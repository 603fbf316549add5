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
