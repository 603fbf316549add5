//! The ground station's side of the onboard link: after every onboard step it sees what the
//! vehicle reports (its outputs, battery, sonar, the revolution just handed over, the flight
//! events logged since its last look) and answers with what the ground sends, which reaches the
//! autopilot at the next step, as a radio link would deliver it between two steps.
//!
//! The simulator knows nothing of the wire: a MAVLink link, a web view or a test script is a
//! [`GroundStation`]. Without one the onboard stack flies exactly as it does alone.

use plumbline_core::flight::events::Event;
use plumbline_core::msgs::{BatterySample, GroundMessages, Outputs, SonarSample};
use plumbline_core::scan::Beam;

/// What the vehicle reports to the ground after one onboard step; everything onboard values,
/// never ground truth.
#[derive(Clone, Copy, Debug)]
pub struct VehicleReport<'a> {
    /// The step's time, s.
    pub t_s: f64,
    /// What the autopilot returned: mode, failsafe, estimate, motors, setpoint.
    pub outputs: &'a Outputs,
    /// The battery as measured at this step.
    pub battery: BatterySample,
    /// A sonar reading, if one arrived since the previous step.
    pub sonar: Option<SonarSample>,
    /// The revolution handed to the stack at this step (body FLU, onboard format), if one
    /// completed; `None` while the lidar is silent.
    pub scan: Option<&'a [Beam]>,
    /// The flight events the autopilot logged since the previous report, oldest first.
    pub events: &'a [Event],
    /// Events pushed out of the autopilot's log before the ground station saw them (a
    /// ground station is called every step, so this stays zero unless the log overflows
    /// within one step).
    pub events_missed: u32,
}

/// A ground station linked to the vehicle.
pub trait GroundStation {
    /// Called after each onboard step with what the vehicle reports; returns what the ground
    /// sent meanwhile, handed to the autopilot at the next step. It must not block: the
    /// vehicle's loop waits for it.
    fn exchange(&mut self, vehicle: &VehicleReport<'_>) -> GroundMessages;
}
