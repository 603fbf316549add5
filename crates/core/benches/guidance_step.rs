//! One guidance step (PRLS segments, gaps, heading rules, velocity field, guard) on a 360-beam
//! revolution, the XV-11's size: what the companion or flight computer spends per revolution
//! (the XV-11 turns at 5 Hz, so the budget is 200 ms).

use criterion::{criterion_group, criterion_main, Criterion};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::guidance::{Guidance, GuidanceConfig, GuidanceMode};
use plumbline_core::scan::Scan;
use std::f32::consts::TAU;
use std::hint::black_box;

#[allow(dead_code)] // the benchmark uses the scenes and the ray caster, not every helper
#[path = "../tests/synthetic/mod.rs"]
mod synthetic;

/// A 2 m corridor with a 1.2 m door on each side and rooms behind them.
fn corridor_with_doors() -> Vec<synthetic::Seg> {
    let w = |a: (f32, f32), b: (f32, f32)| (Vec2::new(a.0, a.1), Vec2::new(b.0, b.1));
    vec![
        w((-20.0, -1.0), (1.0, -1.0)),
        w((2.2, -1.0), (20.0, -1.0)),
        w((-20.0, 1.0), (3.0, 1.0)),
        w((4.2, 1.0), (20.0, 1.0)),
        w((-1.0, -1.0), (-1.0, -5.0)),
        w((-1.0, -5.0), (5.0, -5.0)),
        w((5.0, -5.0), (5.0, -1.0)),
        w((1.0, 1.0), (1.0, 5.0)),
        w((1.0, 5.0), (7.0, 5.0)),
        w((7.0, 5.0), (7.0, 1.0)),
    ]
}

fn guidance_step(c: &mut Criterion) {
    let pose = Pose2::new(0.2, -0.3, 0.1);
    let room: Scan<360> = synthetic::scan_within(&synthetic::room(), pose, 360, TAU, 0.01, 7, 6.0);
    let corridor: Scan<360> =
        synthetic::scan_within(&corridor_with_doors(), pose, 360, TAU, 0.01, 7, 6.0);
    let mut g = Guidance::<64>::new(GuidanceConfig::default()).expect("default config is valid");
    let mut group = c.benchmark_group("guidance_step_360");
    group.bench_function("wall_follow_room", |b| {
        b.iter(|| g.step(black_box(&room), black_box(pose), GuidanceMode::WallFollow))
    });
    group.bench_function("wall_follow_corridor_doors", |b| {
        b.iter(|| {
            g.step(
                black_box(&corridor),
                black_box(pose),
                GuidanceMode::WallFollow,
            )
        })
    });
    let waypoint = GuidanceMode::TowardWaypoint {
        world_m: [2.0, 1.0],
    };
    group.bench_function("toward_waypoint_room", |b| {
        b.iter(|| g.step(black_box(&room), black_box(pose), black_box(waypoint)))
    });
    group.finish();
}

criterion_group!(benches, guidance_step);
criterion_main!(benches);
