//! What every subcommand shares: the `--json` summary line, progress bars, error type.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// A user-facing failure: printed to stderr as one line, exit code 1.
#[derive(Debug)]
pub struct CliError(pub String);

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl<E: std::error::Error> From<E> for CliError {
    fn from(e: E) -> Self {
        CliError(e.to_string())
    }
}

pub type CliResult = Result<(), CliError>;

/// Prints the summary: one JSON object on the last line of stdout with `--json`, otherwise
/// `key: value` lines for people.
pub fn print_summary(summary: &serde_json::Value, json: bool) {
    if json {
        println!("{summary}");
    } else if let Some(map) = summary.as_object() {
        for (k, v) in map {
            println!("{k}: {v}");
        }
    }
}

/// A progress bar on a terminal, and nothing otherwise, so pipes and CI logs stay clean.
pub fn progress(len: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// A progress bar over the bytes of an input file (a spinner when its length is unknown), on a
/// terminal only.
pub fn progress_bytes(total: Option<u64>, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let (bar, template) = match total {
        Some(len) => (
            ProgressBar::new(len),
            "{msg} [{bar:40}] {bytes}/{total_bytes} ({eta})",
        ),
        None => (ProgressBar::new_spinner(), "{msg} {spinner} {bytes}"),
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}
