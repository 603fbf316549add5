//! CARMEN writers. Invalid beams are written as the max range, CARMEN's "no return", so a
//! reader with the same max range marks them invalid again.

use super::LaserRecord;
use std::io::{self, Write};

/// Writes one `ROBOTLASER1` line (it stores the field of view, unlike `FLASER`).
pub fn write_robotlaser1<W: Write + ?Sized>(
    w: &mut W,
    rec: &LaserRecord,
    hostname: &str,
) -> io::Result<()> {
    let n = rec.ranges_m.len();
    let fov = rec.increment_rad * n.saturating_sub(1) as f32;
    write!(
        w,
        "ROBOTLASER1 0 {:.6} {:.6} {:.6} {:.3} 0.010 0 {n}",
        rec.start_angle_rad, fov, rec.increment_rad, rec.max_range_m
    )?;
    for (&r, &ok) in rec.ranges_m.iter().zip(&rec.valid) {
        let r = if ok { r } else { rec.max_range_m };
        write!(w, " {r:.3}")?;
    }
    let p = rec.odom.unwrap_or_default();
    let pose = format!("{:.6} {:.6} {:.6}", p.x_m, p.y_m, p.theta_rad);
    writeln!(
        w,
        " 0 {pose} {pose} 0.000 0.000 0.000 0.000 0.000 {} {hostname} {}",
        rec.timestamp_text, rec.timestamp_text
    )
}
