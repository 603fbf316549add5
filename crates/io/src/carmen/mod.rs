//! CARMEN text logs (the Freiburg / Radish benchmark format), read and written.
//!
//! Layouts are in `DESIGN.md` §5. Readers take `.gz` transparently.

mod record;
mod write;

pub use record::{LaserRecord, OdomPose};
pub use write::write_robotlaser1;
