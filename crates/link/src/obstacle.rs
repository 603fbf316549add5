//! OBSTACLE_DISTANCE from one lidar revolution: 72 sectors of 5 degrees in the body frame, each
//! the nearest valid return in it, in centimetres.
//!
//! MAVLink counts sector angles clockwise from forward (FRD); Plumbline's beams are
//! counter-clockwise from forward (FLU), so a beam at `a` falls in the sector centred at `-a`.
//! Sector 0 is centred on forward (`angle_offset` 0): sector `i` spans `5 i +- 2.5` degrees
//! clockwise. A sector with no valid beam says UINT16_MAX ("no data"), one whose nearest
//! return lies beyond the range limit says `max_distance + 1` ("no obstacle"), per the spec.

use mavlink::dialects::common::{MavDistanceSensor, MavFrame, OBSTACLE_DISTANCE_DATA};
use plumbline_core::scan::Beam;

pub const SECTORS: usize = 72;
const SECTOR_DEG: f32 = 5.0;
const NO_DATA: u16 = u16::MAX;

/// The lidar's usable range, reported in OBSTACLE_DISTANCE's min/max fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleRange {
    /// Returns nearer than this are treated as no data (the sensor's blind zone).
    pub min_m: f32,
    /// Returns farther than this mean "no obstacle in this sector".
    pub max_m: f32,
}

impl Default for ObstacleRange {
    /// The XV-11's datasheet range (0.06 to 5 m); set the device's own for other lidars.
    fn default() -> Self {
        Self {
            min_m: 0.06,
            max_m: 5.0,
        }
    }
}

/// Centimetres, rounded to nearest, saturating (ranges beyond 655 m do not occur and must not
/// wrap). Adding a half and truncating rounds a non-negative value without a libm call, which
/// matters at 360 beams a revolution.
fn to_cm(m: f32) -> u16 {
    (m * 100.0 + 0.5).clamp(0.0, f32::from(u16::MAX - 2)) as u16
}

/// Sectors per radian.
const SECTORS_PER_RAD: f32 = SECTORS as f32 / core::f32::consts::TAU;

/// The sector (0..72) a beam at `angle_rad` (counter-clockwise from forward) falls in.
pub fn sector_of(angle_rad: f32) -> usize {
    // Sector centres every 5 degrees clockwise: floor(x + 1/2) rounds to the nearest centre.
    let x = -angle_rad * SECTORS_PER_RAD + 0.5;
    let mut k = x as i64;
    if (k as f32) > x {
        k -= 1;
    }
    k.rem_euclid(SECTORS as i64) as usize
}

/// The OBSTACLE_DISTANCE message of one revolution.
pub fn obstacle_distance(beams: &[Beam], range: ObstacleRange, t_s: f64) -> OBSTACLE_DISTANCE_DATA {
    let (min_cm, max_cm) = (to_cm(range.min_m), to_cm(range.max_m));
    let mut distances = [NO_DATA; SECTORS];
    for beam in beams {
        if !beam.valid || !beam.angle_rad.is_finite() || beam.range_m < range.min_m {
            continue;
        }
        let cm = if beam.range_m > range.max_m {
            max_cm + 1
        } else {
            to_cm(beam.range_m)
        };
        let d = &mut distances[sector_of(beam.angle_rad)];
        // NO_DATA is the largest u16, so the nearest return wins without a special case.
        *d = (*d).min(cm);
    }
    OBSTACLE_DISTANCE_DATA {
        time_usec: crate::telemetry::usec(t_s),
        distances,
        min_distance: min_cm,
        max_distance: max_cm,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment: SECTOR_DEG as u8,
        increment_f: SECTOR_DEG,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_BODY_FRD,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn left_is_270_degrees_clockwise_and_right_is_90() {
        assert_eq!(sector_of(0.0), 0);
        assert_eq!(sector_of(90f32.to_radians()), 54);
        assert_eq!(sector_of(-90f32.to_radians()), 18);
        assert_eq!(sector_of(180f32.to_radians()), 36);
        // Sector edges: 2.4 degrees clockwise is still sector 0, 2.6 is sector 1.
        assert_eq!(sector_of(-2.4f32.to_radians()), 0);
        assert_eq!(sector_of(-2.6f32.to_radians()), 1);
    }

    #[test]
    fn nearest_return_wins_and_empty_sectors_say_no_data() {
        let beams = [
            Beam::new(0.0, 2.0),
            Beam::new(0.01, 1.5),
            Beam::invalid(0.02),
            Beam::new(90f32.to_radians(), 9.0),
            Beam::new(-90f32.to_radians(), 0.01),
        ];
        let m = obstacle_distance(&beams, ObstacleRange::default(), 1.0);
        assert_eq!(m.distances[0], 150);
        // Beyond the range limit: no obstacle.
        assert_eq!(m.distances[54], 501);
        // Only a return inside the blind zone: no data.
        assert_eq!(m.distances[18], u16::MAX);
        assert_eq!(m.distances.iter().filter(|&&d| d != u16::MAX).count(), 2);
        assert_eq!((m.min_distance, m.max_distance, m.increment), (6, 500, 5));
        assert_eq!(m.frame, MavFrame::MAV_FRAME_BODY_FRD);
    }

    proptest! {
        #[test]
        fn every_angle_lands_in_a_sector_whose_centre_is_within_half_a_sector(a in -10.0f32..10.0) {
            let s = sector_of(a);
            prop_assert!(s < SECTORS);
            let centre_cw = s as f32 * SECTOR_DEG;
            let cw = (-a.to_degrees()).rem_euclid(360.0);
            let diff = (cw - centre_cw + 540.0).rem_euclid(360.0) - 180.0;
            prop_assert!(diff.abs() <= SECTOR_DEG / 2.0 + 1e-3, "{} {} {}", a, s, diff);
        }
    }
}
