//! `plumbline sim` end to end: the files it writes, and that a seed reproduces them bit for bit.

use std::path::Path;
use std::process::Command;

fn sim(dir: &Path, seed: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "sim",
        "--world",
        "room",
        "--scenario",
        "hold",
        "--duration",
        "4",
        "--seed",
        seed,
        "--json",
        "--out",
    ];
    args.push(dir.to_str().unwrap());
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(&args)
        .output()
        .unwrap()
}

const FILES: [&str; 6] = [
    "scans.clf",
    "imu.csv",
    "sonar.csv",
    "truth.txt",
    "truth.relations",
    "top.png",
];

#[test]
fn same_seed_writes_identical_files_and_another_seed_differs() {
    let tmp = std::env::temp_dir().join(format!("plumbline-sim-test-{}", std::process::id()));
    let (a, b, c) = (tmp.join("a"), tmp.join("b"), tmp.join("c"));
    for (dir, seed) in [(&a, "7"), (&b, "7"), (&c, "8")] {
        let out = sim(dir, seed, &[]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let last = String::from_utf8_lossy(&out.stdout)
            .lines()
            .last()
            .unwrap()
            .to_string();
        let summary: serde_json::Value = serde_json::from_str(&last).unwrap();
        assert_eq!(summary["status"], "completed");
        assert!(summary["realtime_factor"].as_f64().unwrap() > 1.0);
        let fractions = &summary["power_fraction"];
        assert!(fractions["motors"].as_f64().unwrap() > 0.9, "{summary}");
    }
    for f in FILES {
        let read = |d: &Path| std::fs::read(d.join(f)).unwrap();
        assert_eq!(
            read(&a),
            read(&b),
            "{f} differs between runs with the same seed"
        );
        if f != "top.png" {
            assert_ne!(read(&a), read(&c), "{f} is the same for another seed");
        }
    }
    // One truth line per scan line, with the same timestamps.
    let clf = std::fs::read_to_string(a.join("scans.clf")).unwrap();
    let truth = std::fs::read_to_string(a.join("truth.txt")).unwrap();
    assert_eq!(clf.lines().count(), truth.lines().count());
    for (scan, pose) in clf.lines().zip(truth.lines()) {
        let stamp = pose.split(' ').next().unwrap();
        assert!(
            scan.ends_with(&format!("{stamp} plumbline-sim {stamp}")),
            "{scan}"
        );
    }
    std::fs::remove_dir_all(&tmp).ok();
}

#[test]
fn bad_world_file_names_the_line() {
    let tmp = std::env::temp_dir().join(format!("plumbline-sim-bad-{}.world", std::process::id()));
    std::fs::write(&tmp, "start 1 1 0\nwall 0 0 1\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(["sim", "--world", tmp.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 2") && err.contains("4 numbers"), "{err}");
    std::fs::remove_file(&tmp).ok();
}

#[test]
fn a_log_rasterises_into_a_world_that_can_be_flown() {
    let tmp = std::env::temp_dir().join(format!("plumbline-sim-raster-{}", std::process::id()));
    let log = tmp.join("box.clf");
    std::fs::create_dir_all(&tmp).unwrap();
    // A robot at two poses in a 6 m x 6 m room scanning 360 degrees: every beam hits a wall.
    let mut text = String::new();
    for (k, x) in [(0, 2.0), (1, 3.0)] {
        let ranges: Vec<String> = (0..360)
            .map(|b| {
                let a = (b as f64).to_radians();
                let (c, s) = (a.cos(), a.sin());
                let tx = if c > 0.0 {
                    (6.0 - x) / c
                } else if c < 0.0 {
                    -x / c
                } else {
                    f64::INFINITY
                };
                let ty = if s > 0.0 {
                    3.0 / s
                } else if s < 0.0 {
                    3.0 / -s
                } else {
                    f64::INFINITY
                };
                format!("{:.3}", tx.min(ty))
            })
            .collect();
        text += &format!(
            "ROBOTLASER1 0 0 6.265732 0.017453 30 0.01 0 360 {} 0 {x} 3 0 {x} 3 0 0 0 0 0 0 {k}.0 host {k}.0\n",
            ranges.join(" ")
        );
    }
    std::fs::write(&log, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args([
            "sim",
            "--rasterize",
            log.to_str().unwrap(),
            "--out",
            tmp.to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let world = tmp.join("box.world");
    let text = std::fs::read_to_string(&world).unwrap();
    assert!(
        text.lines().filter(|l| l.starts_with("wall")).count() >= 4,
        "{text}"
    );
    assert!(tmp.join("box.pgm").exists() && tmp.join("box.yaml").exists());
    let fly = |w: &Path| {
        Command::new(env!("CARGO_BIN_EXE_plumbline"))
            .args([
                "sim",
                "--world",
                w.to_str().unwrap(),
                "--scenario",
                "hold",
                "--duration",
                "2",
                "--json",
            ])
            .output()
            .unwrap()
    };
    for w in [world, tmp.join("box.pgm")] {
        let out = fly(&w);
        assert!(
            out.status.success(),
            "{}: {}",
            w.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("\"status\":\"completed\""));
    }
    std::fs::remove_dir_all(&tmp).ok();
}
