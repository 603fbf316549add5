//! What a flight links to the ground: the MAVLink link (`--mavlink`) and the wall-clock pacing
//! that lets people watch (`--realtime`), both ground stations of the simulator.

use super::mavlink::{signing_key, LinkStats, MavlinkArgs, MavlinkStation};
use super::pace::Pacer;
use crate::numeric::{within, Range};
use crate::report::CliError;
use clap::Args;
use plumbline_sim::runner::ground::GroundStation;
use plumbline_sim::scenario::Flight;
use std::cell::RefCell;
use std::rc::Rc;

#[derive(Args, Debug)]
pub struct GroundArgs {
    #[command(flatten)]
    pub mavlink: MavlinkArgs,
    /// Pace the flight to the wall clock, or FACTOR times faster (`--realtime 10`), so a ground
    /// station sees it fly; without it the flight runs as fast as it computes.
    /// Valid range: (0, 1000].
    #[arg(long, value_name = "FACTOR", num_args = 0..=1, default_missing_value = "1",
          value_parser = within::<f64>(Range::above(0.0, 1000.0)))]
    pub realtime: Option<f64>,
}

/// What was linked, for the summary.
#[derive(Default)]
pub struct Linked {
    pub mavlink: Option<Rc<RefCell<LinkStats>>>,
}

/// Links what `args` ask for to `flight`; refused for a flight without a ground link.
pub fn link(args: &GroundArgs, flight: &mut Flight) -> Result<Linked, CliError> {
    let mut linked = Linked::default();
    let mut stations: Vec<Box<dyn GroundStation>> = Vec::new();
    if let Some(endpoint) = &args.mavlink.mavlink {
        let key = args
            .mavlink
            .mavlink_key
            .as_deref()
            .map(signing_key)
            .transpose()
            .map_err(CliError)?;
        let (station, stats) = MavlinkStation::open(endpoint, key).map_err(CliError)?;
        stations.push(Box::new(station));
        linked.mavlink = Some(stats);
    }
    // Last, so the pause after a step comes once its telemetry has gone out.
    if let Some(speed) = args.realtime {
        stations.push(Box::new(Pacer::new(speed)));
    }
    for station in stations {
        flight.link_ground(station).map_err(|_| {
            CliError(
                "--mavlink and --realtime need a flight by the onboard stack (--controller pid or \
                 mrac, a scenario other than survey); the test pilot has no ground link"
                    .into(),
            )
        })?;
    }
    Ok(linked)
}
