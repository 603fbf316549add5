//! The std-side laser revolution that log readers produce and writers consume.

use plumbline_core::scan::{Beam, Scan, ScanFull};

/// A pose in a log, kept in `f64`: benchmark logs carry offsets like x = 597 m.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OdomPose {
    pub x_m: f64,
    pub y_m: f64,
    pub theta_rad: f64,
}

/// One laser revolution from a log, with equally spaced beams.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserRecord {
    /// The `ipc_timestamp` field: the time the trajectory and relations files refer to.
    pub timestamp_s: f64,
    /// The timestamp text exactly as in the log, so trajectories can copy it unchanged.
    pub timestamp_text: String,
    pub start_angle_rad: f32,
    pub increment_rad: f32,
    /// Readings at or beyond this are "no return" (CARMEN writes max range for misses).
    pub max_range_m: f32,
    pub ranges_m: Vec<f32>,
    /// Per-beam validity; invalid beams keep whatever range the log had.
    pub valid: Vec<bool>,
    /// The robot pose stored with the scan (raw odometry in benchmark logs), if any.
    pub odom: Option<OdomPose>,
}

impl LaserRecord {
    /// Builds a record and derives validity: finite, positive and below `max_range_m`.
    pub fn new(
        timestamp_s: f64,
        start_angle_rad: f32,
        increment_rad: f32,
        max_range_m: f32,
        ranges_m: Vec<f32>,
    ) -> Self {
        let valid = ranges_m
            .iter()
            .map(|&r| r.is_finite() && r > 0.0 && r < max_range_m)
            .collect();
        Self {
            timestamp_s,
            timestamp_text: format!("{timestamp_s:.6}"),
            start_angle_rad,
            increment_rad,
            max_range_m,
            ranges_m,
            valid,
            odom: None,
        }
    }

    pub fn beam_count(&self) -> usize {
        self.ranges_m.len()
    }

    /// Converts to the onboard scan type; fails if the revolution has more than `N` beams.
    pub fn to_scan<const N: usize>(&self) -> Result<Scan<N>, ScanFull> {
        let mut scan = Scan::new(self.timestamp_s);
        for (i, (&r, &ok)) in self.ranges_m.iter().zip(&self.valid).enumerate() {
            let angle = self.start_angle_rad + self.increment_rad * i as f32;
            scan.push(if ok {
                Beam::new(angle, r)
            } else {
                Beam::invalid(angle)
            })?;
        }
        Ok(scan)
    }
}
