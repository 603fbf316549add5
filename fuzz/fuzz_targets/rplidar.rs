//! RPLIDAR standard scan: no panic; every revolution handed out is plausible, every node has a
//! possible angle.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::lidar::rplidar::{RplidarConfig, RplidarDecoder};
use plumbline_core::lidar::ByteDecoder;

fuzz_target!(|data: &[u8]| {
    let mut revs = Vec::new();
    RplidarDecoder::<800>::new().decode_into(data, &mut revs);
    for rev in revs {
        assert!(rev.nodes().iter().all(|n| n.angle_q6 < 360 * 64));
        assert!(rev.is_plausible());
        let _ = rev.to_scan(&RplidarConfig::A1);
    }
});
