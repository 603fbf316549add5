//! ODOMETRY in its two uses: the vehicle's own estimate to a ground station, and a companion
//! computer's lidar pose to an autopilot's EKF (PX4, ArduPilot).

use crate::ned::{
    flip_euler, flip_pose_covariance_upper, flip_quaternion, flip_yz, quaternion_from_euler,
};
use crate::telemetry::usec;
use mavlink::dialects::common::{MavEstimatorType, MavFrame, ODOMETRY_DATA};
use plumbline_core::msgs::{EstimatedState, PoseFix};

/// MAVLink's "this covariance is unknown": NaN in the first element.
fn unknown_covariance() -> [f32; 21] {
    let mut c = [0.0; 21];
    c[0] = f32::NAN;
    c
}

/// The companion's pose fix as the autopilot wants it: pose in MAV_FRAME_LOCAL_FRD (the
/// companion's map, half-turned to FRD like every frame here), child frame MAV_FRAME_BODY_FRD
/// (ArduPilot accepts no other pair), estimator VISION (PX4 refuses LIDAR).
///
/// A 2-D lidar SLAM knows x, y and yaw; what it does not know is sent finite anyway, because
/// both autopilots throw away the whole message's part for one NaN: PX4 drops the position
/// unless x, y and z are all finite, and ArduPilot pools the three position variances (and the
/// three attitude variances) into one error, so a NaN in one poisons the others. So height is
/// the caller's (`height_m` above the map origin, e.g. from a rangefinder) or 0, the map
/// origin's, with the horizontal variance; roll and pitch in the quaternion are zero, with the
/// yaw's variance. Neither autopilot fuses them when set up as the README says (PX4's external
/// vision for horizontal position and yaw only, ArduPilot's height from its barometer; roll and
/// pitch always from their own IMU), and the pooled error then stays the horizontal one.
/// Velocities and rates are unknown (NaN, with NaN first in their covariance): both read them
/// only when finite.
pub fn odometry_from_pose_fix(fix: &PoseFix, height_m: Option<f32>) -> ODOMETRY_DATA {
    let [x, y, z] = flip_yz([
        fix.position_m[0],
        fix.position_m[1],
        height_m.unwrap_or(0.0),
    ]);
    let [roll, pitch, yaw] = flip_euler(0.0, 0.0, fix.yaw_rad);
    // (x, y, yaw) of the fix are pose components 0, 1 and 5.
    let axes = [0usize, 1, 5];
    let mut cov = [[0.0f32; 6]; 6];
    for (a, &i) in axes.iter().enumerate() {
        for (b, &j) in axes.iter().enumerate() {
            cov[i][j] = fix.covariance[a][b];
        }
    }
    cov[2][2] = if height_m.is_some() {
        0.0
    } else {
        cov[0][0].max(cov[1][1])
    };
    cov[3][3] = cov[5][5];
    cov[4][4] = cov[5][5];
    let covariance_known = fix.covariance.iter().flatten().all(|c| c.is_finite());
    ODOMETRY_DATA {
        time_usec: usec(fix.t_s),
        x,
        y,
        z,
        q: quaternion_from_euler(roll, pitch, yaw),
        vx: f32::NAN,
        vy: f32::NAN,
        vz: f32::NAN,
        rollspeed: f32::NAN,
        pitchspeed: f32::NAN,
        yawspeed: f32::NAN,
        pose_covariance: if covariance_known {
            flip_pose_covariance_upper(&cov)
        } else {
            unknown_covariance()
        },
        velocity_covariance: unknown_covariance(),
        frame_id: MavFrame::MAV_FRAME_LOCAL_FRD,
        child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
        reset_counter: fix.reset_counter,
        estimator_type: MavEstimatorType::MAV_ESTIMATOR_TYPE_VISION,
        quality: fix.quality_pct.map_or(-1, |q| q.min(100) as i8),
    }
}

/// The vehicle's own estimate for a ground station: pose in MAV_FRAME_LOCAL_NED (the world
/// frame half-turned, see [`crate::ned`]), velocity in MAV_FRAME_BODY_FRD, body rates from the
/// gyro. Only the position variances are known (the filter's per-axis sigma); the attitude
/// ones are NaN. Quality is 0 ("not rated") while the estimate is valid and -1 once it is not.
pub fn odometry_from_estimate(
    estimate: &EstimatedState,
    body_rates_rad_s: [f32; 3],
    t_s: f64,
) -> ODOMETRY_DATA {
    let [x, y, z] = flip_yz(estimate.position_m);
    let q_enu = quaternion_from_euler(estimate.roll_rad, estimate.pitch_rad, estimate.yaw_rad);
    let [vx, vy, vz] = flip_yz(rotate_into_body(q_enu, estimate.velocity_m_s));
    let [p, q, r] = flip_yz(body_rates_rad_s);
    let mut cov = [[0.0f32; 6]; 6];
    for (i, sigma) in estimate.position_std_m.iter().enumerate() {
        cov[i][i] = sigma * sigma;
    }
    for (i, row) in cov.iter_mut().enumerate().skip(3) {
        row[i] = f32::NAN;
    }
    ODOMETRY_DATA {
        time_usec: usec(t_s),
        x,
        y,
        z,
        q: flip_quaternion(q_enu),
        vx,
        vy,
        vz,
        rollspeed: p,
        pitchspeed: q,
        yawspeed: r,
        pose_covariance: flip_pose_covariance_upper(&cov),
        velocity_covariance: unknown_covariance(),
        frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
        reset_counter: 0,
        estimator_type: MavEstimatorType::MAV_ESTIMATOR_TYPE_LIDAR,
        quality: if estimate.valid { 0 } else { -1 },
    }
}

/// A world-frame vector in the body frame of attitude `q` (world-from-body, `w x y z`).
fn rotate_into_body(q: [f32; 4], v: [f32; 3]) -> [f32; 3] {
    let [w, x, y, z] = q;
    // Rows of R^T (the transpose of the world-from-body rotation matrix).
    let rt = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y + w * z),
            2.0 * (x * z - w * y),
        ],
        [
            2.0 * (x * y - w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z + w * x),
        ],
        [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    rt.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_2;

    #[test]
    fn a_pose_fix_becomes_vision_odometry_in_frd() {
        let fix = PoseFix {
            t_s: 2.5,
            position_m: [1.0, 2.0],
            yaw_rad: FRAC_PI_2,
            covariance: [[0.01, 0.0, 0.001], [0.0, 0.04, 0.0], [0.001, 0.0, 0.0009]],
            quality_pct: Some(87),
            reset_counter: 3,
        };
        let o = odometry_from_pose_fix(&fix, None);
        assert_eq!((o.x, o.y), (1.0, -2.0));
        // Height unknown: the map origin's, with the horizontal variance.
        assert!(o.z == 0.0 && o.vx.is_nan());
        assert_eq!(o.time_usec, 2_500_000);
        assert_eq!(o.frame_id, MavFrame::MAV_FRAME_LOCAL_FRD);
        assert_eq!(o.child_frame_id, MavFrame::MAV_FRAME_BODY_FRD);
        assert_eq!(
            o.estimator_type,
            MavEstimatorType::MAV_ESTIMATOR_TYPE_VISION
        );
        assert_eq!((o.quality, o.reset_counter), (87, 3));
        // Yaw +90 deg ENU is -90 deg NED: q = (cos 45, 0, 0, -sin 45).
        assert!((o.q[0] - 0.70710677).abs() < 1e-6 && (o.q[3] + 0.70710677).abs() < 1e-6);
        // x x, y y, yaw yaw; x-yaw changes sign with yaw, x-y keeps its (zero) value.
        assert_eq!(o.pose_covariance[0], 0.01);
        assert_eq!(o.pose_covariance[6], 0.04);
        assert_eq!(o.pose_covariance[20], 0.0009);
        assert_eq!(o.pose_covariance[5], -0.001);
        assert_eq!(
            o.pose_covariance[11], 0.04,
            "unknown height: the horizontal variance"
        );
        // Roll and pitch are not measured: the yaw's variance, finite for ArduPilot's pooling.
        assert_eq!(
            (o.pose_covariance[15], o.pose_covariance[18]),
            (0.0009, 0.0009)
        );
        assert!(o.pose_covariance.iter().all(|c| c.is_finite()));
        assert!(o.velocity_covariance[0].is_nan());
        let lost = PoseFix {
            quality_pct: None,
            ..fix
        };
        assert_eq!(odometry_from_pose_fix(&lost, Some(1.0)).quality, -1);
        assert_eq!(odometry_from_pose_fix(&lost, Some(1.0)).z, -1.0);
        let unknown = PoseFix {
            covariance: [[f32::NAN; 3]; 3],
            ..fix
        };
        assert!(odometry_from_pose_fix(&unknown, None).pose_covariance[0].is_nan());
    }

    #[test]
    fn the_estimate_reports_body_velocity() {
        // Facing world +y (yaw 90 deg) and moving along world +y: forward in the body.
        let estimate = EstimatedState {
            position_m: [1.0, 2.0, 3.0],
            velocity_m_s: [0.0, 1.0, 0.0],
            yaw_rad: FRAC_PI_2,
            position_std_m: [0.1, 0.2, 0.3],
            valid: true,
            ..Default::default()
        };
        let o = odometry_from_estimate(&estimate, [0.0, 0.0, 0.5], 1.0);
        assert_eq!((o.x, o.y, o.z), (1.0, -2.0, -3.0));
        assert!(
            (o.vx - 1.0).abs() < 1e-6 && o.vy.abs() < 1e-6,
            "{} {}",
            o.vx,
            o.vy
        );
        assert_eq!(o.yawspeed, -0.5);
        assert!((o.pose_covariance[0] - 0.01).abs() < 1e-7);
        assert_eq!(o.frame_id, MavFrame::MAV_FRAME_LOCAL_NED);
        assert_eq!(o.quality, 0);
    }
}
