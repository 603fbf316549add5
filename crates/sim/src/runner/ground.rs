//! The ground station's side of the onboard link: after every onboard step it sees what the
//! vehicle reports (its outputs, battery, sonar, the revolution just handed over, the flight
//! events logged since its last look) and answers with what the ground sends, which reaches the
//! autopilot at the next step, as a radio link would deliver it between two steps.
//!
//! The simulator knows nothing of the wire: a MAVLink link, a web view or a test script is a
//! [`GroundStation`]. Several may be linked at once; without one the onboard stack flies exactly
//! as it does alone.

use plumbline_core::flight::autopilot::Autopilot;
use plumbline_core::flight::events::Event;
use plumbline_core::flight::params::{self, ParamError, ParamInfo};
use plumbline_core::msgs::{
    BatterySample, GroundCommand, GroundMessages, ImuSample, Outputs, SonarSample,
};
use plumbline_core::scan::Beam;
use std::collections::VecDeque;

/// What the vehicle reports to the ground after one onboard step; everything onboard values,
/// never ground truth.
#[derive(Clone, Copy, Debug)]
pub struct VehicleReport<'a> {
    /// The step's time, s.
    pub t_s: f64,
    /// What the autopilot returned: mode, failsafe, estimate, motors, setpoint.
    pub outputs: &'a Outputs,
    /// The newest IMU sample (body FLU; the gyro gives the body rates).
    pub imu: ImuSample,
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

/// The autopilot's tuning as the ground reads and sets it: named, bounded parameters (the
/// registry of [`plumbline_core::flight::params`]). A value is checked against its bounds and
/// the rest of the tuning, and takes effect at the next step.
pub struct Parameters<'a> {
    autopilot: &'a mut Autopilot,
}

impl<'a> Parameters<'a> {
    pub(crate) fn new(autopilot: &'a mut Autopilot) -> Self {
        Self { autopilot }
    }

    pub fn count(&self) -> usize {
        params::count()
    }

    /// Name, unit, bounds and meaning of parameter `index`.
    pub fn info(&self, index: usize) -> Option<&'static ParamInfo> {
        params::info(index)
    }

    /// The value in force of parameter `index`.
    pub fn get(&self, index: usize) -> Option<f32> {
        self.autopilot.param(index)
    }

    /// Sets parameter `index`; returns the value now in force, or why nothing changed.
    pub fn set(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        self.autopilot.set_param(index, value)
    }
}

/// A ground station linked to the vehicle.
pub trait GroundStation {
    /// Called after each onboard step with what the vehicle reports and its parameters;
    /// returns what the ground sent meanwhile, handed to the autopilot at the next step. It
    /// must not block: the vehicle's loop waits for it.
    fn exchange(
        &mut self,
        vehicle: &VehicleReport<'_>,
        parameters: &mut Parameters<'_>,
    ) -> GroundMessages;
}

/// Commands waiting for their step, at most this many; more within a few milliseconds is a
/// flood, and the newest are dropped (the kill switch always gets in).
const COMMAND_QUEUE: usize = 16;

/// The linked stations and what is in flight between them and the autopilot.
pub(crate) struct GroundLink {
    stations: Vec<Box<dyn GroundStation>>,
    /// Commands received, one handed over per step (the autopilot takes one per step).
    commands: VecDeque<GroundCommand>,
    /// A station's heartbeat arrived since the autopilot's last step.
    heartbeat: bool,
    /// The autopilot's event-log total already reported.
    events_seen: u32,
    /// The new events of one step, reused so a step does not allocate.
    new_events: Vec<Event>,
}

impl GroundLink {
    /// A link with no station yet, joining when the autopilot has logged `events_total` events.
    pub(crate) fn new(events_total: u32) -> Self {
        Self {
            stations: Vec::new(),
            commands: VecDeque::with_capacity(COMMAND_QUEUE),
            heartbeat: false,
            events_seen: events_total,
            new_events: Vec::new(),
        }
    }

    pub(crate) fn add(&mut self, station: Box<dyn GroundStation>) {
        self.stations.push(station);
    }

    /// What goes to the autopilot at this step.
    pub(crate) fn uplink(&mut self) -> GroundMessages {
        GroundMessages {
            command: self.commands.pop_front(),
            heartbeat: core::mem::take(&mut self.heartbeat),
        }
    }

    /// Reports a step to every station (`report` without its events: they come from the
    /// autopilot's log) and queues what they sent.
    pub(crate) fn exchange(&mut self, report: VehicleReport<'_>, autopilot: &mut Autopilot) {
        let events = autopilot.events();
        let new = events.total().wrapping_sub(self.events_seen);
        self.events_seen = events.total();
        self.new_events.clear();
        let kept = events.iter().count();
        self.new_events
            .extend(events.iter().skip(kept.saturating_sub(new as usize)));
        let report = VehicleReport {
            events: &self.new_events,
            events_missed: new.saturating_sub(self.new_events.len() as u32),
            ..report
        };
        let mut parameters = Parameters::new(autopilot);
        for station in &mut self.stations {
            let sent = station.exchange(&report, &mut parameters);
            self.heartbeat |= sent.heartbeat;
            match sent.command {
                // The kill switch jumps the queue and is never dropped.
                Some(GroundCommand::Terminate) => {
                    self.commands.truncate(COMMAND_QUEUE - 1);
                    self.commands.push_front(GroundCommand::Terminate);
                }
                Some(c) if self.commands.len() < COMMAND_QUEUE => self.commands.push_back(c),
                _ => {}
            }
        }
    }
}
