//! Links the binary without the C runtime's start files (its `_start` is in `main.rs`), static
//! and at a fixed address, as firmware is; and copies the first revolutions of a real XV-11
//! capture for it to decode.

use std::env;
use std::fs;
use std::path::PathBuf;

/// About twelve revolutions (90 packets of 22 bytes each).
const CAPTURE_BYTES: usize = 24_000;

fn main() {
    for arg in ["-nostartfiles", "-static", "-no-pie"] {
        println!("cargo:rustc-link-arg-bins={arg}");
    }
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let capture = manifest.join("../../data/captures/neato-xv11/hand_in_box.bin");
    println!("cargo:rerun-if-changed={}", capture.display());
    let bytes = fs::read(&capture)
        .unwrap_or_else(|e| panic!("{}: {e} (the bundled XV-11 capture)", capture.display()));
    let out = PathBuf::from(env::var("OUT_DIR").expect("set by cargo")).join("capture.bin");
    fs::write(&out, &bytes[..CAPTURE_BYTES.min(bytes.len())])
        .unwrap_or_else(|e| panic!("{}: {e}", out.display()));
}
