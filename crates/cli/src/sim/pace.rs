//! `--realtime`: the flight paced to the wall clock, so a ground station or a web view sees it
//! as it would fly. Linked as a ground station that sends nothing: it only waits, after a step,
//! until the wall clock has caught up with the simulated one.

use plumbline_core::msgs::GroundMessages;
use plumbline_sim::runner::ground::{GroundStation, Parameters, VehicleReport};
use std::time::{Duration, Instant};

/// Sleeps shorter than this are skipped (and made up at a later step): the kernel's sleep is
/// not finer, and the onboard loop steps every 2 ms.
const MIN_SLEEP: Duration = Duration::from_millis(2);

/// Holds the flight to `speed` simulated seconds per wall-clock second.
pub struct Pacer {
    speed: f64,
    /// The wall clock at simulated time `t0_s`.
    started: Option<(Instant, f64)>,
}

impl Pacer {
    pub fn new(speed: f64) -> Self {
        Self {
            speed,
            started: None,
        }
    }
}

impl GroundStation for Pacer {
    fn exchange(&mut self, vehicle: &VehicleReport<'_>, _: &mut Parameters<'_>) -> GroundMessages {
        let (wall0, t0_s) = *self.started.get_or_insert((Instant::now(), vehicle.t_s));
        let due = Duration::from_secs_f64(((vehicle.t_s - t0_s) / self.speed).max(0.0));
        if let Some(ahead) = due.checked_sub(wall0.elapsed()) {
            if ahead >= MIN_SLEEP {
                std::thread::sleep(ahead);
            }
        }
        GroundMessages::default()
    }
}
