//! Simulator speed: the real-time factor of the office survey with the XV-11
//! at 1 kHz physics, and ray casting against a 200-wall world.
//!
//! Criterion reports throughput: for `survey` the elements are physics steps (1 ms each), so the
//! real-time factor is elements per second / 1000; for `rays` the elements are rays. `rays/*`
//! casts each ray on its own through the scene's grid; `rays/*_scans` casts the same rays the way
//! the lidar does, 360 beams per place through [`Nearby`], its set-up at every place included.
//! For `dynamics` the elements are RK4 steps of the rigid body and motors alone.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use plumbline_sim::math::Vec3;
use plumbline_sim::runner::plan::{Plan, PlanLimits};
use plumbline_sim::runner::{run, Discard, Pilot, SimConfig};
use plumbline_sim::sensors::lidar::LidarProfile;
use plumbline_sim::vehicle::dynamics::{BodyState, Dynamics, Forcing};
use plumbline_sim::vehicle::VehicleParams;
use plumbline_sim::world::nearby::Nearby;
use plumbline_sim::world::scene::Scene;
use plumbline_sim::world::World;
use std::hint::black_box;

fn survey(c: &mut Criterion) {
    let world = World::shipped("office").unwrap().unwrap();
    let config = SimConfig::new(world, LidarProfile::xv11(), 7);
    let plan = Plan::survey(&config.world, PlanLimits::default());
    let steps = run(&config, Pilot::Test(plan.clone()), &mut Discard)
        .unwrap()
        .physics_steps;
    let mut g = c.benchmark_group("survey");
    g.sample_size(10);
    g.throughput(Throughput::Elements(steps));
    g.bench_function("office_xv11_1khz", |b| {
        b.iter(|| run(&config, Pilot::Test(plan.clone()), &mut Discard).unwrap())
    });
    g.finish();
}

/// The rigid body and motors alone: 1,000 RK4 steps of 1 ms around hover, the commands changing
/// at every step. What the survey's physics costs without sensors, pilot or bookkeeping.
fn dynamics(c: &mut Criterion) {
    let p = VehicleParams::f450();
    let d = Dynamics::new(&p, [1.0, 1.02, 0.98, 1.01], 1e-3);
    let hover = p.hover_rotor_speed() / p.max_rotor_speed_radps;
    let start = BodyState {
        motor: [hover; 4],
        rotor_speed: [hover * p.max_rotor_speed_radps; 4],
        ..BodyState::at_rest(Vec3::new(0.0, 0.0, 1.0), 0.3)
    };
    let mut g = c.benchmark_group("dynamics");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("rk4_1khz", |b| {
        b.iter(|| {
            let mut s = start;
            for k in 0..1000 {
                let wobble = 0.01 * ((k % 7) as f64 - 3.0);
                let f = Forcing {
                    command: [
                        hover + wobble,
                        hover - wobble,
                        hover + wobble,
                        hover - wobble,
                    ],
                    ..Forcing::default()
                };
                s = d.step(black_box(&s), &f);
            }
            s
        })
    });
    g.finish();
}

/// A 10 x 10 grid of 4 m rooms: 2 x 10 x 10 walls, each a room side with a 1 m door gap.
fn grid_world() -> World {
    let mut text = String::from("start 2 2 0\nceiling 2.5\n");
    for i in 0..10 {
        for j in 0..10 {
            let (x, y) = (i as f64 * 4.0, j as f64 * 4.0);
            text += &format!("wall {x} {y} {} {y}\n", x + 3.0);
            text += &format!("wall {x} {y} {x} {}\n", y + 3.0);
        }
    }
    World::parse(&text).unwrap()
}

fn rays(c: &mut Criterion) {
    let world = grid_world();
    assert_eq!(world.walls.len(), 200);
    let scene = Scene::new(&world);
    let origins: Vec<Vec3> = (0..64)
        .map(|k| Vec3::new(1.0 + (k % 8) as f64 * 4.7, 1.5 + (k / 8) as f64 * 4.3, 1.0))
        .collect();
    let dirs: Vec<Vec3> = (0..360)
        .map(|b| {
            let (s, c) = (b as f64).to_radians().sin_cos();
            Vec3::new(c * 0.999, s * 0.999, -0.0447)
        })
        .collect();
    let mut g = c.benchmark_group("rays");
    g.throughput(Throughput::Elements((origins.len() * dirs.len()) as u64));
    for (name, range) in [("200_walls_4m", 4.0), ("200_walls_30m", 30.0)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut sum = 0.0;
                for o in &origins {
                    for d in &dirs {
                        sum += scene.cast(*o, *d, range, &[]).map_or(0.0, |h| h.range_m);
                    }
                }
                black_box(sum)
            })
        });
        g.bench_function(format!("{name}_scans"), |b| {
            b.iter(|| {
                let mut near = Nearby::new(range);
                let mut sum = 0.0;
                for o in &origins {
                    for d in &dirs {
                        sum += near
                            .cast(&scene, *o, *d, range, &[])
                            .map_or(0.0, |h| h.range_m);
                    }
                }
                black_box(sum)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, survey, dynamics, rays);
criterion_main!(benches);
