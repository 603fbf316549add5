//! CARMEN log reader: arbitrary text is a parsed log or an error naming a line, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_io::carmen::{parse_log, ReadOptions};

fuzz_target!(|data: &[u8]| {
    for skip_bad_lines in [false, true] {
        let opts = ReadOptions {
            skip_bad_lines,
            ..ReadOptions::default()
        };
        if let Ok(log) = parse_log(data, "fuzz", &opts) {
            assert!(log.scans.iter().all(|s| s.ranges_m.len() == s.valid.len()));
        }
    }
});
