//! Flight control: PID loops, rate damping, the position-to-rate cascade, its approximate
//! inversion, the model-reference adaptive alternative to its outer loops, and the mixer.
//!
//! Pure algorithms (DESIGN.md §2): each takes state, setpoint and `dt` and returns an output;
//! the autopilot in [`crate::flight`] owns timing and modes.

pub mod airframe;
pub mod cascade;
mod cascade_config;
pub mod inversion;
pub mod mixer;
pub mod mrac;
pub mod pid;
pub mod sas;
