//! `plumbline sim --view` in a real browser: headless Chromium (Debian's `chromium`) driven by
//! Playwright from the repository's `.venv` (both installed by scripts/setup.sh), running
//! tests/web_view/browser.py. Loopback only.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::BIN;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs one case of the browser script and fails with its output unless it passes.
fn browser(case: &str) {
    let python = repo().join(".venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run scripts/setup.sh to install Playwright for the web view tests",
        python.display()
    );
    assert!(
        Path::new("/usr/bin/chromium").is_file(),
        "/usr/bin/chromium is missing: run scripts/setup.sh to install Chromium for the web view tests"
    );
    let out = Command::new(&python)
        .arg(repo().join("tests/web_view/browser.py"))
        .arg(BIN)
        .arg(case)
        .output()
        .expect("start python");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "browser {case} failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
}

#[test]
fn the_page_shows_the_map_and_a_moving_pose_read_only() {
    browser("read-only");
}

#[test]
fn the_kill_button_needs_the_token_and_stops_the_motors() {
    browser("commands");
}
