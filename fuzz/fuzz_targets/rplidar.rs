//! RPLIDAR standard scan: no panic; every node handed out has a possible angle.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::lidar::rplidar::{RplidarConfig, RplidarDecoder};

fuzz_target!(|data: &[u8]| {
    let mut d = RplidarDecoder::<800>::new();
    let revs: Vec<_> = data.iter().filter_map(|&b| d.push(b)).chain(d.finish()).collect();
    for rev in revs {
        assert!(rev.nodes().iter().all(|n| n.angle_q6 < 360 * 64));
        let _ = rev.to_scan(&RplidarConfig::A1);
    }
});
