//! Hokuyo SCIP 2.0 replies: no panic; scans convert without exceeding their buffer.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::lidar::scip::{ScipDecoder, UrgConfig};

fuzz_target!(|data: &[u8]| {
    let mut d = ScipDecoder::<769>::new();
    for &b in data {
        if let Some(scan) = d.push(b) {
            assert_eq!(
                scan.to_scan(&UrgConfig::URG_04LX).len(),
                scan.ranges_mm().len()
            );
        }
    }
});
