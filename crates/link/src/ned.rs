//! The one place where Plumbline's frames meet MAVLink's.
//!
//! Inside Plumbline the world frame is ENU-like with x "forward at start" (not east), y left and
//! z up, and the body frame is FLU (DESIGN.md §3). MAVLink's local frames are NED and its body
//! frame FRD. With no compass indoors there is no true north, so the local NED frame used on the
//! wire is defined from Plumbline's world frame by a half turn about x:
//!
//! ```text
//! x_ned = x_world    y_ned = -y_world    z_ned = -z_world
//! x_frd = x_flu      y_frd = -y_flu      z_frd = -z_flu
//! ```
//!
//! so "north" is the direction the vehicle faced at start. The same half turn maps FLU to FRD,
//! which keeps the two conversions one function and makes each its own inverse. Angles follow:
//! roll is unchanged, pitch and yaw change sign (a heading counter-clockwise from world x is
//! clockwise from NED x), body rates `(p, q, r)` become `(p, -q, -r)` and a quaternion
//! `(w, x, y, z)` becomes `(w, x, -y, -z)`. Everything that crosses the MAVLink boundary in
//! either direction goes through this module.

/// The half turn about x, applied to a vector: world ENU to local NED, body FLU to FRD, and back.
pub fn flip_yz(v: [f32; 3]) -> [f32; 3] {
    [v[0], -v[1], -v[2]]
}

/// Euler angles (roll, pitch, yaw; ZYX order, radians) of an ENU/FLU attitude as NED/FRD angles,
/// and back: the half turn keeps roll and negates pitch and yaw.
pub fn flip_euler(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> [f32; 3] {
    [roll_rad, -pitch_rad, -yaw_rad]
}

/// A quaternion `(w, x, y, z)` of an ENU-from-FLU rotation as an NED-from-FRD one, and back
/// (conjugation by the half turn about x).
pub fn flip_quaternion(q: [f32; 4]) -> [f32; 4] {
    [q[0], q[1], -q[2], -q[3]]
}

/// The quaternion `(w, x, y, z)` of ZYX Euler angles (yaw about z, then pitch about y, then roll
/// about x), in whatever frame the angles are given.
pub fn quaternion_from_euler(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> [f32; 4] {
    let (sr, cr) = (roll_rad * 0.5).sin_cos();
    let (sp, cp) = (pitch_rad * 0.5).sin_cos();
    let (sy, cy) = (yaw_rad * 0.5).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// The yaw (ZYX order) of a quaternion `(w, x, y, z)`, in whatever frame it is given: the
/// heading an autopilot's attitude quaternion says, before the half turn. NaN when the
/// quaternion has no direction (zero or non-finite), so the caller's finiteness check refuses it.
pub fn yaw_from_quaternion(q: [f32; 4]) -> f32 {
    let [w, x, y, z] = q;
    let (s, c) = (2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
    let norm2 = w * w + x * x + y * y + z * z;
    if !(norm2.is_finite() && norm2 > 0.0) {
        return f32::NAN;
    }
    // For a quaternion of norm n, c carries 1 - 2(y^2 + z^2) where n^2 should stand; taking
    // it as n^2 - 2(y^2 + z^2) keeps the angle right for a slightly unnormalised one.
    s.atan2(c - 1.0 + norm2)
}

/// Sign of each pose component `(x, y, z, roll, pitch, yaw)` under the half turn; a covariance
/// element `(i, j)` changes by the product of the two signs.
const POSE_SIGNS: [f32; 6] = [1.0, -1.0, -1.0, 1.0, -1.0, -1.0];

/// A 6x6 pose covariance (row-major, `x y z roll pitch yaw`) under the half turn, as MAVLink's
/// upper-triangle layout of 21 values (row by row: (0,0), (0,1), ... (0,5), (1,1), ...).
pub fn flip_pose_covariance_upper(cov: &[[f32; 6]; 6]) -> [f32; 21] {
    let mut out = [0.0; 21];
    let mut k = 0;
    for i in 0..6 {
        for j in i..6 {
            out[k] = cov[i][j] * POSE_SIGNS[i] * POSE_SIGNS[j];
            k += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::{FRAC_PI_2, PI};
    use proptest::prelude::*;

    fn close(a: &[f32], b: &[f32], tol: f32) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    /// Rotates a vector by a quaternion (w, x, y, z).
    fn rotate(q: [f32; 4], v: [f32; 3]) -> [f32; 3] {
        let [w, x, y, z] = q;
        let m = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
    }

    #[test]
    fn known_positions_and_headings() {
        // One metre left of the start point is one metre "west" (negative y_ned).
        assert_eq!(flip_yz([0.0, 1.0, 0.0]), [0.0, -1.0, 0.0]);
        // Two metres up is z_ned = -2.
        assert_eq!(flip_yz([3.0, 0.0, 2.0]), [3.0, 0.0, -2.0]);
        // Facing the start direction is heading 0 in both; a quarter turn left (ENU yaw +90 deg)
        // is NED yaw -90 deg.
        assert_eq!(flip_euler(0.0, 0.0, 0.0), [0.0, 0.0, 0.0]);
        assert_eq!(flip_euler(0.0, 0.0, FRAC_PI_2)[2], -FRAC_PI_2);
        // Nose down is a positive FLU pitch (about the left axis) and a negative FRD one.
        assert_eq!(flip_euler(0.1, 0.2, 0.0), [0.1, -0.2, 0.0]);
    }

    #[test]
    fn a_quarter_turn_left_points_body_forward_along_negative_y_ned() {
        let q_enu = quaternion_from_euler(0.0, 0.0, FRAC_PI_2);
        let q_ned = flip_quaternion(q_enu);
        let forward_ned = rotate(q_ned, [1.0, 0.0, 0.0]);
        assert!(
            close(&forward_ned, &[0.0, -1.0, 0.0], 1e-6),
            "{forward_ned:?}"
        );
    }

    #[test]
    fn the_yaw_of_a_quaternion_is_its_heading() {
        // A quarter turn right in NED (facing east): yaw +90 deg, whatever the roll and pitch.
        let east = quaternion_from_euler(0.2, -0.1, FRAC_PI_2);
        assert!((yaw_from_quaternion(east) - FRAC_PI_2).abs() < 1e-6);
        // Facing south: the half turn, at +pi or -pi.
        let south = yaw_from_quaternion([0.0, 0.0, 0.0, 1.0]);
        assert!((south.abs() - PI).abs() < 1e-6, "{south}");
        // Twice the length: the same heading.
        let q = quaternion_from_euler(0.0, 0.0, -0.7).map(|v| 2.0 * v);
        assert!((yaw_from_quaternion(q) + 0.7).abs() < 1e-6);
        // No rotation to read.
        assert!(yaw_from_quaternion([0.0; 4]).is_nan());
        assert!(yaw_from_quaternion([f32::NAN, 0.0, 0.0, 0.0]).is_nan());
        assert!(yaw_from_quaternion([f32::INFINITY, 0.0, 0.0, 1.0]).is_nan());
    }

    #[test]
    fn covariance_signs_follow_the_axes() {
        let mut cov = [[0.0f32; 6]; 6];
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, c) in row.iter_mut().enumerate() {
                *c = (i * 6 + j + 1) as f32;
            }
        }
        let upper = flip_pose_covariance_upper(&cov);
        assert_eq!(upper[0], 1.0); // x x
        assert_eq!(upper[1], -2.0); // x y
        assert_eq!(upper[6], 8.0); // y y
        assert_eq!(upper[5], -6.0); // x yaw
        assert_eq!(upper[20], 36.0); // yaw yaw
    }

    proptest! {
        #[test]
        fn vectors_and_angles_round_trip(
            x in -1e3f32..1e3, y in -1e3f32..1e3, z in -1e3f32..1e3,
            roll in -PI..PI, pitch in -1.5f32..1.5, yaw in -PI..PI,
        ) {
            prop_assert_eq!(flip_yz(flip_yz([x, y, z])), [x, y, z]);
            let back = flip_euler(roll, pitch, yaw);
            prop_assert_eq!(flip_euler(back[0], back[1], back[2]), [roll, pitch, yaw]);
            let q = quaternion_from_euler(roll, pitch, yaw);
            prop_assert_eq!(flip_quaternion(flip_quaternion(q)), q);
            // The heading read back from a quaternion, flipped, is the heading flipped.
            let read = yaw_from_quaternion(flip_quaternion(q));
            let d = (read + yaw).rem_euclid(2.0 * PI);
            prop_assert!(d.min(2.0 * PI - d) < 1e-4, "{} vs {}", read, -yaw);
        }

        #[test]
        fn the_quaternion_and_the_angles_describe_the_same_rotation(
            roll in -PI..PI, pitch in -1.5f32..1.5, yaw in -PI..PI,
            vx in -1f32..1.0, vy in -1f32..1.0, vz in -1f32..1.0,
        ) {
            // Rotating a body vector in ENU and flipping the result must equal flipping the
            // vector and rotating it by the NED attitude built from the flipped angles.
            let v = [vx, vy, vz];
            let via_enu = flip_yz(rotate(quaternion_from_euler(roll, pitch, yaw), v));
            let e = flip_euler(roll, pitch, yaw);
            let via_ned = rotate(quaternion_from_euler(e[0], e[1], e[2]), flip_yz(v));
            prop_assert!(close(&via_enu, &via_ned, 1e-5), "{:?} vs {:?}", via_enu, via_ned);
            let q = flip_quaternion(quaternion_from_euler(roll, pitch, yaw));
            let via_q = rotate(q, flip_yz(v));
            prop_assert!(close(&via_enu, &via_q, 1e-5), "{:?} vs {:?}", via_enu, via_q);
        }
    }
}
