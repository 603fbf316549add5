//! Freiburg relations files: `t1 t2 x y z roll pitch yaw`, the pose at t2 in the frame of the
//! pose at t1 (Kuemmerle et al. 2009). Only the planar part (x, y, yaw) is used.

use crate::carmen::{OdomPose, ReadError};
use crate::text_table::read_rows;
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relation {
    pub t1_s: f64,
    pub t2_s: f64,
    /// Reference motion from the pose at t1 to the pose at t2, in the frame of the pose at t1.
    pub motion: OdomPose,
}

pub fn read_relations(path: &Path) -> Result<Vec<Relation>, ReadError> {
    let mut out = Vec::new();
    read_rows(path, 8, |row| {
        let v = &row.values;
        out.push(Relation {
            t1_s: v[0],
            t2_s: v[1],
            motion: OdomPose {
                x_m: v[2],
                y_m: v[3],
                theta_rad: v[7],
            },
        });
        Ok(())
    })?;
    Ok(out)
}

/// Writes relations in the same layout, z, roll and pitch zero.
pub fn write_relations<W: std::io::Write + ?Sized>(
    w: &mut W,
    relations: &[Relation],
) -> std::io::Result<()> {
    for r in relations {
        writeln!(
            w,
            "{:.6} {:.6} {:.6} {:.6} 0.000000 0.000000 0.000000 {:.6}",
            r.t1_s, r.t2_s, r.motion.x_m, r.motion.y_m, r.motion.theta_rad
        )?;
    }
    Ok(())
}
