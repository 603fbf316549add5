//! One controller step, PID next to MRAC, on the same hovering state with a small offset.
//!
//! Each is a whole cascade step with the outer loops run on that call (`outer_period_s = 0`):
//! the worst case of the 500 Hz loop (in flight the outer loops run at 100 Hz). The two differ
//! only in the outer law (`--controller pid|mrac`): the PID's position and velocity loops, or
//! the MRAC's step (hedge, reference model, RBF network and its learning update); inversion,
//! attitude and rate loops are shared. Every iteration starts from a copy of a cascade that has
//! flown 50 steps (reference model running, hedge active, weights learning), so the MRAC never
//! reaches its weight bound and falls back to the cheaper baseline mid-measurement.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use plumbline_core::control::cascade::{Cascade, CascadeConfig, CascadeSetpoint, Vertical};
use plumbline_core::control::mixer::Demand;
use plumbline_core::control::mrac::MracConfig;
use plumbline_core::msgs::EstimatedState;
use std::hint::black_box;

fn state() -> EstimatedState {
    EstimatedState {
        position_m: [0.05, -0.03, 0.97],
        velocity_m_s: [0.1, 0.02, -0.05],
        roll_rad: 0.01,
        pitch_rad: -0.02,
        yaw_rad: 0.3,
        valid: true,
        ..Default::default()
    }
}

const SETPOINT: CascadeSetpoint = CascadeSetpoint {
    horizontal_m: Some([0.0, 0.0]),
    feed_forward: None,
    vertical: Vertical::Height(1.0),
    yaw_rad: 0.3,
};

fn every_step() -> CascadeConfig {
    CascadeConfig {
        outer_period_s: 0.0,
        ..CascadeConfig::default()
    }
}

fn steps(c: &mut Criterion) {
    let s = state();
    let gyro = [0.01, -0.02, 0.0];
    let dt = 0.002;
    let pid = Cascade::new(every_step());
    let mut mrac = Cascade::with_mrac(every_step(), MracConfig::default()).unwrap();
    // Airborne, with a hedge to compute, as in flight.
    let hover = Demand {
        collective: 0.35,
        ..Demand::default()
    };
    mrac.actuated(&hover, true);

    let mut g = c.benchmark_group("cascade_step");
    for (name, mut warm) in [("pid", pid), ("mrac", mrac)] {
        for _ in 0..50 {
            let _ = warm.run(&SETPOINT, &s, gyro, dt, true);
            warm.actuated(&hover, true);
        }
        g.bench_function(name, |b| {
            b.iter_batched_ref(
                || warm,
                |cascade| cascade.run(black_box(&SETPOINT), black_box(&s), gyro, dt, true),
                BatchSize::SmallInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
