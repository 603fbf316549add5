//! Trajectories: one line per scan, `timestamp x y theta`, the timestamp copied exactly from the
//! scan it belongs to (DESIGN.md §5).

use crate::carmen::{OdomPose, ReadError};
use crate::text_table::read_rows;
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryPoint {
    pub timestamp_text: String,
    pub timestamp_s: f64,
    pub pose: OdomPose,
}

pub fn write_trajectory<W: std::io::Write + ?Sized>(
    w: &mut W,
    points: &[TrajectoryPoint],
) -> std::io::Result<()> {
    for p in points {
        writeln!(
            w,
            "{} {:.6} {:.6} {:.6}",
            p.timestamp_text, p.pose.x_m, p.pose.y_m, p.pose.theta_rad
        )?;
    }
    Ok(())
}

pub fn read_trajectory(path: &Path) -> Result<Vec<TrajectoryPoint>, ReadError> {
    let mut out = Vec::new();
    read_rows(path, 4, |row| {
        let v = &row.values;
        out.push(TrajectoryPoint {
            timestamp_text: row.first_text.to_string(),
            timestamp_s: v[0],
            pose: OdomPose {
                x_m: v[1],
                y_m: v[2],
                theta_rad: v[3],
            },
        });
        Ok(())
    })?;
    Ok(out)
}
