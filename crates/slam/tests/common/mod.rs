//! Scans of a known room shared by the integration tests.

use plumbline_core::geom::Pose2;
use plumbline_core::scan::Beam;

/// Beams from `pose` to the walls of the axis-aligned room [0, w] x [0, h] (exact ranges),
/// evenly spread over the full turn.
pub fn room_scan(pose: Pose2, w: f32, h: f32, beams: usize) -> Vec<Beam> {
    (0..beams)
        .map(|k| {
            let a = k as f32 * core::f32::consts::TAU / beams as f32 - core::f32::consts::PI;
            let (dx, dy) = ((pose.theta + a).cos(), (pose.theta + a).sin());
            let tx = if dx > 0.0 {
                (w - pose.x) / dx
            } else {
                -pose.x / dx
            };
            let ty = if dy > 0.0 {
                (h - pose.y) / dy
            } else {
                -pose.y / dy
            };
            Beam::new(a, tx.min(ty))
        })
        .collect()
}
