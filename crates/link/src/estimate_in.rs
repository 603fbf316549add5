//! The autopilot's own estimate as a companion computer reads it back: ODOMETRY, or
//! LOCAL_POSITION_NED with ATTITUDE for the heading (what PX4 and ArduPilot stream to a
//! companion port), turned from NED/FRD into Plumbline's ENU/FLU through [`crate::ned`].
//!
//! Only the conversion happens here; whether a sample is fresh, continuous and usable is
//! [`crate::EstimateWatch`]'s to judge, so a NaN field passes through as NaN.

use crate::ned::{flip_euler, flip_yz, yaw_from_quaternion};
use mavlink::dialects::common::{MavFrame, MavMessage};

/// ODOMETRY's content: position and heading of one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryPose {
    pub position_m: [f32; 3],
    pub yaw_rad: f32,
    /// False when the autopilot says the estimate failed (quality -1) or gives it in a frame
    /// this side cannot read (anything but a local z-down frame: LOCAL_NED, LOCAL_FRD).
    pub valid: bool,
    /// Goes up when the autopilot's estimate jumped.
    pub reset_counter: u8,
}

/// What one message said about the autopilot's estimate, in Plumbline's frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimatePart {
    /// ODOMETRY.
    Pose(OdometryPose),
    /// LOCAL_POSITION_NED: the position alone (the autopilot stops sending it while it has
    /// none).
    Position { position_m: [f32; 3] },
    /// ATTITUDE: the heading alone.
    Heading { yaw_rad: f32 },
}

/// One message's estimate with the autopilot's own stamp of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimateSample {
    /// The autopilot's clock (s): `time_usec` of ODOMETRY, `time_boot_ms` of the others.
    /// Comparable only between samples of the same kind.
    pub autopilot_s: f64,
    pub part: EstimatePart,
}

/// The estimate in `message`, if it carries one.
pub fn estimate_sample(message: &MavMessage) -> Option<EstimateSample> {
    let boot_s = |ms: u32| f64::from(ms) * 1e-3;
    match message {
        MavMessage::ODOMETRY(o) => {
            let readable = matches!(
                o.frame_id,
                MavFrame::MAV_FRAME_LOCAL_NED | MavFrame::MAV_FRAME_LOCAL_FRD
            );
            Some(EstimateSample {
                autopilot_s: o.time_usec as f64 * 1e-6,
                part: EstimatePart::Pose(OdometryPose {
                    position_m: flip_yz([o.x, o.y, o.z]),
                    yaw_rad: flip_euler(0.0, 0.0, yaw_from_quaternion(o.q))[2],
                    valid: readable && o.quality != -1,
                    reset_counter: o.reset_counter,
                }),
            })
        }
        MavMessage::LOCAL_POSITION_NED(p) => Some(EstimateSample {
            autopilot_s: boot_s(p.time_boot_ms),
            part: EstimatePart::Position {
                position_m: flip_yz([p.x, p.y, p.z]),
            },
        }),
        MavMessage::ATTITUDE(a) => Some(EstimateSample {
            autopilot_s: boot_s(a.time_boot_ms),
            part: EstimatePart::Heading {
                yaw_rad: flip_euler(a.roll, a.pitch, a.yaw)[2],
            },
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ned::quaternion_from_euler;
    use core::f32::consts::FRAC_PI_2;
    use mavlink::dialects::common::{ATTITUDE_DATA, LOCAL_POSITION_NED_DATA, ODOMETRY_DATA};

    fn odometry(x: f32, y: f32, yaw_ned: f32) -> ODOMETRY_DATA {
        ODOMETRY_DATA {
            time_usec: 2_500_000,
            x,
            y,
            z: -1.5,
            q: quaternion_from_euler(0.05, -0.02, yaw_ned),
            frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
            child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
            quality: 80,
            reset_counter: 4,
            ..Default::default()
        }
    }

    #[test]
    fn ned_positions_and_headings_become_enu_ones() {
        // Two metres north and one east, facing east (NED yaw +90 deg), 1.5 m up: in ENU-like
        // axes x 2, y -1 (east is to the right of north), z 1.5, heading -90 deg.
        let s = estimate_sample(&MavMessage::ODOMETRY(odometry(2.0, 1.0, FRAC_PI_2))).unwrap();
        assert_eq!(s.autopilot_s, 2.5);
        let EstimatePart::Pose(OdometryPose {
            position_m,
            yaw_rad,
            valid,
            reset_counter,
        }) = s.part
        else {
            panic!("{s:?}");
        };
        assert_eq!(position_m, [2.0, -1.0, 1.5]);
        assert!((yaw_rad + FRAC_PI_2).abs() < 1e-6, "{yaw_rad}");
        assert!(valid);
        assert_eq!(reset_counter, 4);

        let p = LOCAL_POSITION_NED_DATA {
            time_boot_ms: 1234,
            x: -3.0,
            y: -0.5,
            z: -2.0,
            ..Default::default()
        };
        let s = estimate_sample(&MavMessage::LOCAL_POSITION_NED(p)).unwrap();
        assert_eq!(s.autopilot_s, 1.234);
        assert_eq!(
            s.part,
            EstimatePart::Position {
                position_m: [-3.0, 0.5, 2.0]
            }
        );
        // Facing north-west (NED yaw -45 deg) is 45 deg counter-clockwise in ENU.
        let a = ATTITUDE_DATA {
            time_boot_ms: 1240,
            yaw: -0.785,
            ..Default::default()
        };
        let s = estimate_sample(&MavMessage::ATTITUDE(a)).unwrap();
        assert_eq!(s.part, EstimatePart::Heading { yaw_rad: 0.785 });
        assert_eq!(
            estimate_sample(&MavMessage::HEARTBEAT(Default::default())),
            None
        );
    }

    #[test]
    fn a_failed_or_unreadable_odometry_is_marked_invalid() {
        let valid = |o: ODOMETRY_DATA| match estimate_sample(&MavMessage::ODOMETRY(o)) {
            Some(EstimateSample {
                part: EstimatePart::Pose(OdometryPose { valid, .. }),
                ..
            }) => valid,
            other => panic!("{other:?}"),
        };
        let good = odometry(0.0, 0.0, 0.0);
        assert!(valid(good.clone()));
        assert!(valid(ODOMETRY_DATA {
            quality: 0,
            frame_id: MavFrame::MAV_FRAME_LOCAL_FRD,
            ..good.clone()
        }));
        assert!(!valid(ODOMETRY_DATA {
            quality: -1,
            ..good.clone()
        }));
        assert!(!valid(ODOMETRY_DATA {
            frame_id: MavFrame::MAV_FRAME_LOCAL_ENU,
            ..good.clone()
        }));
        // A NaN passes through for the watch to refuse.
        let nan = ODOMETRY_DATA {
            q: [f32::NAN; 4],
            ..good
        };
        match estimate_sample(&MavMessage::ODOMETRY(nan)).unwrap().part {
            EstimatePart::Pose(OdometryPose { yaw_rad, .. }) => assert!(yaw_rad.is_nan()),
            other => panic!("{other:?}"),
        }
    }
}
