//! `plumbline sim --view` and `plumbline companion --view` in a real browser: headless Chromium (Debian's `chromium`) driven by
//! Playwright from the repository's `.venv` (both installed by scripts/setup.sh), running
//! tests/web_view/browser.py. Loopback only.

mod support;

use std::path::Path;
use support::{venv_script, BIN};

fn browser(case: &str) {
    assert!(
        Path::new("/usr/bin/chromium").is_file(),
        "/usr/bin/chromium is missing: run scripts/setup.sh to install Chromium for the web view tests"
    );
    venv_script(
        "tests/web_view/browser.py",
        &[BIN, case],
        "Playwright for the web view tests",
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

#[test]
fn the_companion_serves_its_map_and_pose_read_only() {
    browser("companion");
}
