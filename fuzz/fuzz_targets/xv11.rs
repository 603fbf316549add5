//! XV-11 (fw >= 2.4): no panic, and byte-wise `push` agrees with slice `feed`.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::lidar::xv11_revolution::Xv11Decoder;
use plumbline_core::lidar::ByteDecoder;

fuzz_target!(|data: &[u8]| {
    let mut bytewise = Xv11Decoder::new();
    let mut a = Vec::new();
    bytewise.decode_into(data, &mut a);
    let mut sliced = Xv11Decoder::new();
    let mut b = Vec::new();
    let mut rest = data;
    while !rest.is_empty() {
        let (n, rev) = sliced.feed(rest);
        rest = &rest[n..];
        b.extend(rev);
    }
    b.extend(sliced.finish());
    assert_eq!(a, b);
    assert_eq!(bytewise.stats(), sliced.stats());
    for rev in &a {
        assert_eq!(rev.to_scan(0.0).len(), 360);
    }
});
