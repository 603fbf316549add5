//! A simulation that is refused must leave nothing behind: every check (the world, the start,
//! the vehicle, the rates, the scenario) runs before the first output file is created, so a
//! rejected run never leaves an empty or half-written `imu.csv`, `sonar.csv`, `scans.clf` or
//! `truth.txt` in `--out` for someone to mistake for a flight.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A 6 m x 4 m room with a cabinet; `start` is the take-off line.
fn world(start: &str) -> String {
    format!(
        "name hostile\nceiling 2.5\n{start}\naltitude 1\noutline 0 0 6 0 6 4 0 4\n\
         box 4 2.5 5 3.5\npath 2 2 3 2\n"
    )
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plumbline-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `plumbline sim` on `world_text` with `--out` inside a scratch folder; returns stderr
/// and the output folder.
fn refused(name: &str, world_text: &str, extra: &[&str]) -> (String, PathBuf) {
    let dir = scratch(name);
    let world_file = dir.join("hostile.world");
    std::fs::write(&world_file, world_text).unwrap();
    let out_dir = dir.join("out");
    let mut args = vec![
        "sim",
        "--world",
        world_file.to_str().unwrap(),
        "--duration",
        "2",
        "--out",
        out_dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(&args)
        .output()
        .unwrap();
    assert!(!out.status.success(), "{name}: the run was not refused");
    (String::from_utf8_lossy(&out.stderr).into_owned(), out_dir)
}

/// The files in `dir` (none when it does not exist).
fn left_behind(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn a_start_inside_a_block_is_refused_before_any_file_is_written() {
    let (err, out) = refused("block", &world("start 4.5 3 0"), &[]);
    assert!(err.contains("start") && err.contains("inside"), "{err}");
    assert_eq!(left_behind(&out), Vec::<String>::new(), "{err}");
}

#[test]
fn a_start_on_a_wall_is_refused_before_any_file_is_written() {
    for scenario in ["survey", "hold"] {
        let (err, out) = refused(scenario, &world("start 0.1 2 0"), &["--scenario", scenario]);
        assert!(err.contains("start") && err.contains("wall"), "{err}");
        assert_eq!(left_behind(&out), Vec::<String>::new(), "{scenario}: {err}");
    }
}

#[test]
fn a_physics_rate_too_low_is_refused_before_any_file_is_written() {
    // The command line refuses it while it is read (the simulator's own check is for library
    // callers); either way nothing is written.
    let (err, out) = refused("rate", &world("start 2 2 0"), &["--physics-hz", "50"]);
    assert!(
        err.contains("--physics-hz") && err.contains("[100, 20000]"),
        "{err}"
    );
    assert_eq!(left_behind(&out), Vec::<String>::new(), "{err}");
}
