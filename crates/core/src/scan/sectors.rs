//! The nearest obstacle around the vehicle, one distance per sector of a revolution: what an
//! autopilot's obstacle avoidance takes (MAVLink OBSTACLE_DISTANCE carries 72 of them).
//!
//! Kept in Plumbline's convention (body FLU, angles counter-clockwise from body x); the MAVLink
//! layer turns the sectors clockwise (FRD) when it encodes them.

use super::Scan;
use crate::geom::normalize_angle;
use core::f32::consts::TAU;

/// Sectors per turn: 5 degrees each, the resolution MAVLink OBSTACLE_DISTANCE carries in a
/// whole turn.
pub const SECTOR_COUNT: usize = 72;

/// Width of one sector (rad).
pub const SECTOR_WIDTH_RAD: f32 = TAU / SECTOR_COUNT as f32;

/// The nearest return in every sector of one revolution, in the body frame.
///
/// Sector `i` is centred on `i * SECTOR_WIDTH_RAD` counter-clockwise from body x (sector 0
/// straight ahead, 18 on the left, 54 on the right) and spans half a width either side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleSectors {
    /// Time of the revolution's first beam (s), the scan's stamp.
    pub t_s: f64,
    /// Nearest valid return in each sector (m); `None` where no beam returned (a blind
    /// sector, nothing in range, or all beams flagged): unknown, never "free".
    pub nearest_m: [Option<f32>; SECTOR_COUNT],
}

impl ObstacleSectors {
    /// The sector a bearing (rad, counter-clockwise from body x, any turn) falls in.
    pub fn sector_of(angle_rad: f32) -> usize {
        let a = normalize_angle(angle_rad);
        let turns = if a < 0.0 { a + TAU } else { a } / SECTOR_WIDTH_RAD;
        // `+ 0.5` centres sector 0 on straight ahead; the last half-sector wraps to 0.
        (libm::floorf(turns + 0.5) as usize) % SECTOR_COUNT
    }

    /// The nearest valid return of `scan` in every sector.
    pub fn from_scan<const N: usize>(scan: &Scan<N>) -> Self {
        let mut nearest_m = [None; SECTOR_COUNT];
        for beam in scan.beams().iter().filter(|b| b.valid) {
            let slot: &mut Option<f32> = &mut nearest_m[Self::sector_of(beam.angle_rad)];
            if slot.is_none_or(|r| beam.range_m < r) {
                *slot = Some(beam.range_m);
            }
        }
        Self {
            t_s: scan.stamp_s,
            nearest_m,
        }
    }

    /// The nearest return of the whole revolution (m), if any beam returned.
    pub fn nearest(&self) -> Option<f32> {
        self.nearest_m.iter().flatten().copied().reduce(f32::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::Beam;

    #[test]
    fn sectors_are_centred_counter_clockwise_from_ahead() {
        let deg = |d: f32| d.to_radians();
        assert_eq!(ObstacleSectors::sector_of(0.0), 0);
        assert_eq!(ObstacleSectors::sector_of(deg(2.4)), 0);
        assert_eq!(ObstacleSectors::sector_of(deg(-2.4)), 0);
        assert_eq!(ObstacleSectors::sector_of(deg(2.6)), 1);
        assert_eq!(ObstacleSectors::sector_of(deg(90.0)), 18);
        assert_eq!(ObstacleSectors::sector_of(deg(-90.0)), 54);
        assert_eq!(ObstacleSectors::sector_of(deg(180.0)), 36);
        assert_eq!(ObstacleSectors::sector_of(deg(-177.6)), 36);
        assert_eq!(ObstacleSectors::sector_of(deg(450.0)), 18);
    }

    #[test]
    fn each_sector_keeps_its_nearest_valid_return_and_blind_ones_stay_unknown() {
        let mut scan: Scan<8> = Scan::new(3.5);
        for beam in [
            Beam::new(0.01, 2.0),
            Beam::new(-0.01, 1.5),
            Beam::invalid(0.0),
            Beam::new(core::f32::consts::FRAC_PI_2, 0.7),
        ] {
            scan.push(beam).unwrap();
        }
        let s = ObstacleSectors::from_scan(&scan);
        assert_eq!(s.t_s, 3.5);
        assert_eq!(s.nearest_m[0], Some(1.5));
        assert_eq!(s.nearest_m[18], Some(0.7));
        assert_eq!(s.nearest_m.iter().flatten().count(), 2);
        assert_eq!(s.nearest(), Some(0.7));
        assert_eq!(ObstacleSectors::from_scan(&Scan::<4>::new(0.0)).nearest(), None);
    }

    proptest::proptest! {
        #[test]
        fn any_bearing_lands_in_the_sector_whose_centre_is_nearest(a in -20.0f32..20.0) {
            let s = ObstacleSectors::sector_of(a);
            proptest::prop_assert!(s < SECTOR_COUNT);
            let centre = s as f32 * SECTOR_WIDTH_RAD;
            let off = normalize_angle(a - centre).abs();
            proptest::prop_assert!(off <= 0.5 * SECTOR_WIDTH_RAD + 1e-4, "{a} -> {s} off {off}");
        }
    }
}
