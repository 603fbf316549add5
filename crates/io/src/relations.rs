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

/// Writes planar relations in the same layout, z, roll and pitch zero.
pub fn write_relations<W: std::io::Write + ?Sized>(
    w: &mut W,
    relations: &[Relation],
) -> std::io::Result<()> {
    for r in relations {
        write_relation_3d(
            w,
            &Relation3d {
                t1_s: r.t1_s,
                t2_s: r.t2_s,
                translation_m: [r.motion.x_m, r.motion.y_m, 0.0],
                roll_pitch_yaw_rad: [0.0, 0.0, r.motion.theta_rad],
            },
        )?;
    }
    Ok(())
}

/// A relation in full 3-D (ground truth from a simulator): translation and ZYX Euler angles of
/// the pose at t2 in the frame of the pose at t1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relation3d {
    pub t1_s: f64,
    pub t2_s: f64,
    pub translation_m: [f64; 3],
    pub roll_pitch_yaw_rad: [f64; 3],
}

/// Writes one relations line, times and values to the microsecond and micrometre.
pub fn write_relation_3d<W: std::io::Write + ?Sized>(
    w: &mut W,
    r: &Relation3d,
) -> std::io::Result<()> {
    let ([x, y, z], [roll, pitch, yaw]) = (r.translation_m, r.roll_pitch_yaw_rad);
    writeln!(
        w,
        "{:.6} {:.6} {x:.6} {y:.6} {z:.6} {roll:.6} {pitch:.6} {yaw:.6}",
        r.t1_s, r.t2_s
    )
}
