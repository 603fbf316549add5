//! The flight software proper: modes, failsafes, the event log and the one step function.

pub mod autopilot;
pub mod events;
pub mod level;
pub mod onboard;
pub mod supervisor;
pub mod sweep;
#[cfg(test)]
mod test_vehicle;
#[cfg(test)]
mod tests;
