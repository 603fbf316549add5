//! Ground-truth relations between scans (Kuemmerle et al. 2009, the Freiburg relations format):
//! the pose at t2 expressed in the frame of the pose at t1, in full 3-D.

use crate::math::Vec3;
use crate::runner::TruthPose;

/// One relation: translation (m) and ZYX Euler angles (rad) of pose 2 in the frame of pose 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relation3 {
    pub t1_s: f64,
    pub t2_s: f64,
    pub translation: Vec3,
    pub roll: f64,
    pub pitch: f64,
    pub yaw: f64,
}

/// The relative pose inverse(a) * b.
pub fn relation(a: &TruthPose, b: &TruthPose) -> Relation3 {
    let q = a.attitude.conj() * b.attitude;
    let (roll, pitch, yaw) = q.to_euler();
    Relation3 {
        t1_s: a.t_s,
        t2_s: b.t_s,
        translation: a.attitude.rotate_inv(b.position - a.position),
        roll,
        pitch,
        yaw,
    }
}

/// Relations "near and far in time": every consecutive pair of scans, and from every fifth scan
/// to the first scan at least `far_s` seconds later (long relations expose drift that short
/// ones average away).
pub fn relations(poses: &[TruthPose], far_s: f64) -> Vec<Relation3> {
    let mut out: Vec<Relation3> = poses.windows(2).map(|w| relation(&w[0], &w[1])).collect();
    for (i, a) in poses.iter().enumerate().step_by(5) {
        if let Some(b) = poses[i..].iter().find(|b| b.t_s >= a.t_s + far_s) {
            out.push(relation(a, b));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn relation_is_expressed_in_the_first_frame() {
        let a = TruthPose {
            t_s: 1.0,
            position: Vec3::new(1.0, 1.0, 1.0),
            attitude: Quat::from_euler(0.0, 0.0, core::f64::consts::FRAC_PI_2),
        };
        let b = TruthPose {
            t_s: 2.0,
            position: Vec3::new(1.0, 3.0, 1.5),
            attitude: Quat::from_euler(0.0, 0.0, core::f64::consts::PI),
        };
        let r = relation(&a, &b);
        // Facing +y, a point 2 m along world +y is 2 m straight ahead; the turn is +90 degrees.
        assert!(
            (r.translation - Vec3::new(2.0, 0.0, 0.5)).norm() < 1e-12,
            "{r:?}"
        );
        assert!((r.yaw - core::f64::consts::FRAC_PI_2).abs() < 1e-12 && r.roll.abs() < 1e-12);
    }

    #[test]
    fn near_and_far_pairs() {
        let poses: Vec<TruthPose> = (0..100)
            .map(|i| TruthPose {
                t_s: i as f64 * 0.25,
                position: Vec3::new(i as f64, 0.0, 0.0),
                attitude: Quat::IDENTITY,
            })
            .collect();
        let r = relations(&poses, 10.0);
        assert_eq!(r.iter().filter(|r| r.t2_s - r.t1_s == 0.25).count(), 99);
        let far: Vec<_> = r.iter().filter(|r| r.t2_s - r.t1_s >= 10.0).collect();
        assert_eq!(
            far.len(),
            12,
            "scans 0, 5, ..., 55 have a partner 10 s later"
        );
        assert!(far.iter().all(|r| (r.translation.x - 40.0).abs() < 1e-12));
    }
}
