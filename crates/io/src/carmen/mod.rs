//! CARMEN text logs (the Freiburg / Radish benchmark format), read and written.
//!
//! Layouts are in `DESIGN.md` §5. Readers take gzip transparently (recognised by content).

mod fov;
mod line;
mod read;
mod record;
mod write;

pub use fov::FovRule;
pub use read::{
    open_log, parse_log, read_log, CarmenLog, LogItem, LogReader, OdomRecord, ReadError,
    ReadOptions, ReadStats, FLASER_MAX_RANGE_M,
};
pub use record::{LaserRecord, OdomPose};
pub use write::write_robotlaser1;
