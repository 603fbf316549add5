//! What the command-line suites share: the binary, scratch directories, runs with a memory cap,
//! the repository's small recorded inputs, and virtual serial ports.
#![allow(dead_code)] // each suite uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

pub const BIN: &str = env!("CARGO_BIN_EXE_plumbline");
pub const REPO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

pub fn capture() -> PathBuf {
    Path::new(REPO).join("data/captures/neato-xv11/hand_in_box.bin")
}

pub fn excerpt() -> PathBuf {
    Path::new(REPO).join("data/intel-excerpt.clf")
}

/// The full benchmark logs beside the repository, or `None` after printing why the test skips.
pub fn shared_data() -> Option<PathBuf> {
    let d = Path::new(REPO).join("../shared/data");
    if d.is_dir() {
        Some(d)
    } else {
        println!(
            "skipped: {} does not exist (the full logs are not on this machine)",
            d.display()
        );
        None
    }
}

/// A fresh, empty scratch directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plumbline-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the binary with these arguments.
pub fn run<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// Flies `world` for one second with the simulator's test pilot, writing into `out` if given.
pub fn fly(world: &Path, out: Option<&Path>) -> Output {
    let mut args = vec!["sim", "--world", p(world), "--controller", "test-pilot"];
    args.extend(["--duration", "1"]);
    if let Some(dir) = out {
        args.extend(["--out", p(dir)]);
    }
    run(&args)
}

/// Runs the binary under a 1 GiB address-space cap, so a run that would read an endless input
/// into memory fails fast instead of exhausting the machine.
pub fn run_capped(args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1048576; exec \"$0\" \"$@\"")
        .arg(BIN)
        .args(args)
        .output()
        .unwrap()
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The summary: the last line of stdout, as JSON.
pub fn last_json(out: &Output) -> serde_json::Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap_or_else(|e| {
        panic!(
            "no JSON summary ({e}); stdout {stdout:?}, stderr {}",
            stderr(out)
        )
    })
}

/// Runs the binary, which must succeed, and returns its summary.
pub fn ok_json(args: &[&str]) -> serde_json::Value {
    let out = run(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    last_json(&out)
}

/// The names in a directory, sorted (hidden ones too: a leftover staging file is a failure).
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

pub fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A `socat` process joining two pseudo-terminals, `a` and `b`; killed when dropped.
pub struct Socat {
    child: std::process::Child,
    pub a: PathBuf,
    pub b: PathBuf,
}

impl Drop for Socat {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts socat in `dir`; `None`, with the reason printed, where it cannot run.
pub fn socat_pair(dir: &Path, test: &str) -> Option<Socat> {
    let (a, b) = (dir.join("dev-a"), dir.join("dev-b"));
    let spawned = Command::new("socat")
        .arg(format!("pty,raw,echo=0,link={}", a.display()))
        .arg(format!("pty,raw,echo=0,link={}", b.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn();
    let child = match spawned {
        Ok(child) => child,
        Err(e) => {
            println!("SKIPPED {test}: socat not runnable ({e}); scripts/setup.sh installs it");
            return None;
        }
    };
    let socat = Socat { child, a, b };
    let start = Instant::now();
    while !(socat.a.exists() && socat.b.exists()) {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "socat made no pty pair within 5 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    Some(socat)
}

/// Runs a real-client test script (`tests/...`, relative to the repository) with the Python of
/// the repository's `.venv` and `args`; fails with its output unless it passes. `needs` says
/// what scripts/setup.sh installs for it, for the message when the venv is missing.
pub fn venv_script(script: &str, args: &[&str], needs: &str) {
    let python = Path::new(REPO).join(".venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run scripts/setup.sh to install {needs}",
        python.display()
    );
    let out = Command::new(&python)
        .arg(Path::new(REPO).join(script))
        .args(args)
        .output()
        .expect("start python");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{script} {args:?} failed ({}):\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}
