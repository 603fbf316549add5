//! The flight software proper: modes, failsafes, the event log and the one step function.

pub mod autopilot;
mod autopilot_config;
pub mod events;
pub mod ground;
pub mod mission;
pub mod onboard;
mod param_table;
pub mod params;
mod setpoint_guard;
pub mod supervisor;
#[cfg(test)]
mod test_vehicle;
#[cfg(test)]
mod mission_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod ground_flight_tests;
