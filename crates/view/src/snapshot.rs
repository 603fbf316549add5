//! What the vehicle's loop hands the view: the state at one instant, in the world frame (ENU,
//! metres, radians; DESIGN.md §2).

use plumbline_core::msgs::{FailsafeReason, FlightMode};
use std::sync::Arc;

/// Grey level of a cell nobody has seen.
pub const UNKNOWN: u8 = 128;
/// Grey level of a free cell.
pub const FREE: u8 = 255;
/// Grey level of an occupied cell.
pub const OCCUPIED: u8 = 0;

/// An occupancy map as a grey image: one byte per cell ([`FREE`], [`OCCUPIED`], [`UNKNOWN`] or
/// anything between), row-major, row 0 along the lowest y.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccupancyImage {
    /// Bumped by the producer whenever the cells change; the view sends a map only when it
    /// sees a new version.
    pub version: u64,
    /// World position of the corner of cell (0, 0), m.
    pub origin_m: [f64; 2],
    /// Cell side, m.
    pub resolution_m: f64,
    pub width: usize,
    pub height: usize,
    pub cells: Vec<u8>,
}

impl OccupancyImage {
    /// Whether the image can be drawn: sizes agree and the geometry is finite and positive.
    pub fn is_consistent(&self) -> bool {
        self.width > 0
            && self.height > 0
            && self.width.checked_mul(self.height) == Some(self.cells.len())
            && self.resolution_m.is_finite()
            && self.resolution_m > 0.0
            && self.origin_m.iter().all(|v| v.is_finite())
    }
}

/// The vehicle's state at one instant, as the page shows it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// Vehicle time, s.
    pub t_s: f64,
    /// Where the vehicle believes it is: x, y, z (m) and heading (rad, counter-clockwise from x).
    pub pose: [f64; 4],
    /// Whether the estimate is trustworthy.
    pub estimate_valid: bool,
    /// The latest revolution's hits in the world frame, m.
    pub scan_m: Vec<[f32; 2]>,
    /// Battery voltage, V, when one is known.
    pub battery_v: Option<f32>,
    /// The flight mode; `None` where it is not known (a companion computer beside another
    /// autopilot).
    pub mode: Option<FlightMode>,
    pub failsafe: Option<FailsafeReason>,
    /// The map to draw under the vehicle; shared so publishing it again costs nothing.
    pub map: Option<Arc<OccupancyImage>>,
}
