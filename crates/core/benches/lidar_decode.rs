//! Lidar decoding throughput on the real XV-11 captures (target: >= 100 MB/s of XV-11 bytes on
//! one core; the device sends about 6 KB/s). Criterion reports bytes per second.
//!
//! `packets` runs the byte parser alone, `revolutions` adds revolution assembly, `scans` also
//! converts every revolution to a `Scan<360>` (what a driver hands to the matcher); these feed
//! slices, as a file reader or a DMA buffer does. `revolutions_byte_by_byte` is the one-byte
//! `push` a UART interrupt would use.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use plumbline_core::lidar::xv11::PacketParser;
use plumbline_core::lidar::xv11_old::Xv11OldDecoder;
use plumbline_core::lidar::xv11_revolution::{Revolution, Xv11Decoder};
use std::hint::black_box;

const CAPTURES: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/captures/neato-xv11"
);

fn read(name: &str) -> Vec<u8> {
    let path = format!("{CAPTURES}/{name}");
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Every revolution in `bytes` through `Xv11Decoder::feed`, each passed to `each`.
fn feed_all(bytes: &[u8], mut each: impl FnMut(Revolution)) {
    let mut d = Xv11Decoder::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let (n, rev) = d.feed(rest);
        rest = &rest[n..];
        rev.into_iter().for_each(&mut each);
    }
}

fn xv11(c: &mut Criterion) {
    let bytes = read("hand_in_box.bin");
    let mut g = c.benchmark_group("xv11_hand_in_box");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("packets", |b| {
        b.iter(|| {
            let (mut p, mut rest, mut n) = (PacketParser::new(), black_box(&bytes[..]), 0);
            while !rest.is_empty() {
                let (used, packet) = p.push_slice(rest);
                rest = &rest[used..];
                n += usize::from(packet.is_some());
            }
            n
        })
    });
    g.bench_function("revolutions", |b| {
        b.iter(|| {
            let mut n = 0;
            feed_all(black_box(&bytes), |r| n += r.packets());
            n
        })
    });
    g.bench_function("scans", |b| {
        b.iter(|| {
            let mut n = 0;
            feed_all(black_box(&bytes), |r| n += r.to_scan(0.0).valid_count());
            n
        })
    });
    g.bench_function("revolutions_byte_by_byte", |b| {
        b.iter(|| {
            let mut d = Xv11Decoder::new();
            black_box(&bytes).iter().filter_map(|&x| d.push(x)).count()
        })
    });
    g.finish();
}

fn xv11_old(c: &mut Criterion) {
    let bytes = read("sparkfun_noshield_dump_oldfw.bin");
    let mut g = c.benchmark_group("xv11_old_sparkfun");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("revolutions", |b| {
        b.iter(|| {
            let mut d = Xv11OldDecoder::new();
            black_box(&bytes).iter().filter_map(|&x| d.push(x)).count()
        })
    });
    g.finish();
}

criterion_group!(benches, xv11, xv11_old);
criterion_main!(benches);
