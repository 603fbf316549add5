//! Helpers shared by the lidar integration tests.

use plumbline_core::lidar::{ByteDecoder, DecodeStats};

pub const CAPTURES: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/captures/neato-xv11"
);

/// A capture's bytes; the path in the panic message when it is missing.
pub fn capture(name: &str) -> Vec<u8> {
    let path = format!("{CAPTURES}/{name}");
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Every revolution a fresh `D` makes of `bytes` (the stream ended), and its counters.
pub fn decode<D: ByteDecoder + Default>(bytes: &[u8]) -> (Vec<D::Revolution>, DecodeStats) {
    let mut d = D::default();
    let mut out = Vec::new();
    d.decode_into(bytes, &mut out);
    (out, d.stats())
}
