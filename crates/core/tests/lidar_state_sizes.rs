//! Decoder state sizes: the RAM an embedded build pays per device (printed with
//! `cargo test -p plumbline-core --test lidar_state_sizes -- --nocapture`, bounded here so a
//! change that grows them is a deliberate one).

use core::mem::size_of;
use plumbline_core::lidar::rplidar::{RplidarDecoder, RplidarRevolution};
use plumbline_core::lidar::scip::{ScipDecoder, ScipScan};
use plumbline_core::lidar::xv11_old::Xv11OldDecoder;
use plumbline_core::lidar::xv11_revolution::{Revolution, Xv11Decoder, BEAMS};
use plumbline_core::scan::Scan;

/// URG-04LX: steps 0..=768.
const URG_STEPS: usize = 769;
/// RPLIDAR A1/A2 standard scan: about 360-400 nodes a turn at 2-4 kHz; twice that for margin.
const RPLIDAR_NODES: usize = 800;

#[test]
fn decoder_state_sizes_are_small_and_documented() {
    let rows = [
        ("Xv11Decoder (fw >= 2.4)", size_of::<Xv11Decoder>(), 1_700),
        (
            "Xv11OldDecoder (fw < 2.4)",
            size_of::<Xv11OldDecoder>(),
            3_200,
        ),
        (
            "ScipDecoder<769> (URG-04LX)",
            size_of::<ScipDecoder<URG_STEPS>>(),
            3_400,
        ),
        (
            "RplidarDecoder<800>",
            size_of::<RplidarDecoder<RPLIDAR_NODES>>(),
            5_000,
        ),
        ("xv11 Revolution (output)", size_of::<Revolution>(), 1_500),
        (
            "ScipScan<769> (output)",
            size_of::<ScipScan<URG_STEPS>>(),
            3_100,
        ),
        (
            "RplidarRevolution<800> (output)",
            size_of::<RplidarRevolution<RPLIDAR_NODES>>(),
            4_900,
        ),
        ("Scan<360> (converted)", size_of::<Scan<BEAMS>>(), 5_800),
    ];
    for (name, bytes, bound) in rows {
        println!("{name:34} {bytes:6} bytes (bound {bound})");
        assert!(bytes <= bound, "{name}: {bytes} bytes > {bound}");
    }
}
