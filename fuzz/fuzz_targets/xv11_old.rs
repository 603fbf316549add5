//! XV-11 before fw 2.4: no panic; every frame handed out converts to 360 beams.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::lidar::xv11_old::Xv11OldDecoder;
use plumbline_core::lidar::ByteDecoder;

fuzz_target!(|data: &[u8]| {
    let mut revs = Vec::new();
    Xv11OldDecoder::new().decode_into(data, &mut revs);
    for rev in revs {
        assert_eq!(rev.to_scan(0.0).len(), 360);
    }
});
