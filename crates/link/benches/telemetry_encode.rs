//! Encoding the full telemetry set of one step: every periodic message once (HEARTBEAT,
//! SYS_STATUS, BATTERY_STATUS, ATTITUDE, LOCAL_POSITION_NED, ODOMETRY, DISTANCE_SENSOR,
//! OBSTACLE_DISTANCE from a 360-beam scan) plus the STATUSTEXT of a mode change, into a reused
//! buffer, unsigned and signed. Every rate is set far above the step rate so all streams are
//! due at every call, and the mode alternates so the STATUSTEXT goes out every time.
//!
//! Each variant is measured twice: wall time (criterion's default) and the thread's CPU time
//! (`.../cpu`), which leaves out the time the benchmark spends descheduled on a busy machine.

use criterion::{criterion_group, criterion_main, Criterion};
use plumbline_core::msgs::{BatterySample, EstimatedState, FlightMode, Outputs, SonarSample};
use plumbline_core::scan::Beam;
use plumbline_link::{Link, LinkConfig, LinkTime, SigningKey, TelemetryInput, TelemetryRates};
use std::hint::black_box;
use std::time::Duration;

/// CPU time this thread has used.
fn thread_cpu_time() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec to write into; the clock id is a constant Linux knows.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

fn every_step() -> TelemetryRates {
    let hz = 1e6;
    TelemetryRates {
        heartbeat_hz: hz,
        sys_status_hz: hz,
        battery_status_hz: hz,
        attitude_hz: hz,
        local_position_hz: hz,
        odometry_hz: hz,
        distance_sensor_hz: hz,
        obstacle_distance_hz: hz,
    }
}

fn outputs(mode: FlightMode) -> Outputs {
    Outputs {
        mode,
        estimate: EstimatedState {
            position_m: [1.2, -0.4, 1.0],
            velocity_m_s: [0.3, 0.1, 0.0],
            roll_rad: 0.02,
            pitch_rad: -0.01,
            yaw_rad: 0.7,
            position_std_m: [0.05, 0.05, 0.02],
            valid: true,
        },
        ..Default::default()
    }
}

fn bench(c: &mut Criterion) {
    let scan: Vec<Beam> = (0..360)
        .map(|i| Beam::new((i as f32).to_radians(), 1.0 + (i % 17) as f32 * 0.2))
        .collect();
    let modes = [outputs(FlightMode::Hold), outputs(FlightMode::Explore)];
    for (name, key) in [
        ("telemetry_step_unsigned", None),
        (
            "telemetry_step_signed",
            Some(SigningKey {
                secret: [7; 32],
                link_id: 0,
            }),
        ),
    ] {
        let mut link = Link::new(LinkConfig {
            rates: every_step(),
            key,
            ..LinkConfig::default()
        });
        let mut out = Vec::with_capacity(4096);
        let mut step = 0u64;
        let mut one_step = |link: &mut Link, out: &mut Vec<u8>| {
            step += 1;
            let input = TelemetryInput {
                outputs: &modes[(step % 2) as usize],
                body_rates_rad_s: [0.01, -0.02, 0.3],
                battery: Some(BatterySample {
                    t_s: 0.0,
                    voltage_v: 11.4,
                }),
                sonar: Some(SonarSample {
                    t_s: 0.0,
                    range_m: 1.0,
                }),
                scan: Some(&scan),
            };
            out.clear();
            let now = LinkTime::since(1.7e9, step as f64 * 0.005);
            link.telemetry(black_box(&input), now, out);
            black_box(out.len())
        };
        c.bench_function(name, |b| b.iter(|| one_step(&mut link, &mut out)));
        c.bench_function(&format!("{name}/cpu"), |b| {
            b.iter_custom(|iters| {
                let start = thread_cpu_time();
                for _ in 0..iters {
                    one_step(&mut link, &mut out);
                }
                thread_cpu_time() - start
            })
        });
        // Every message of the set went out at the last call.
        assert!(out.len() > 500, "{}", out.len());
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
