//! Levelling: a scan taken with the vehicle tilted, projected onto the horizontal plane, and
//! de-skewed to mid-revolution ([`super::sweep`]) in the same pass over the beams.
//!
//! A tilted scan plane meets vertical walls further away than the horizontal distance (by
//! 1/cos(tilt)), which the matcher would read as motion. Each hit is rotated by roll and pitch
//! (ZYX, FLU) and its horizontal range and bearing kept; bearings stay continuous with the
//! original ones. De-skewing can reorder a few beams while the vehicle moves; those are dropped
//! so the revolution keeps the angular order the matcher needs.
//!
//! A scan plane tilted far enough meets the floor: at 1 m, 13 degrees of pitch puts the floor
//! 4.3 m ahead, nearer than the far wall of a 7 m hall. Such a return is not a wall, and where
//! it falls moves with the tilt, so the matcher would read the floor's line sweeping toward the
//! vehicle as motion. Given the scan plane's height above the floor, each hit's height is known
//! too, and a hit at floor level (within what the tilt and height errors allow) is dropped
//! ([`FloorReturns`]).
//!
//! This runs on every beam of every revolution (43,000 beams a second from a UTM-30LX), so it
//! avoids per-beam library trigonometry: a device's beams come at the same angles every
//! revolution, so their sines and cosines are kept from the last scan (checked beam by beam and
//! recomputed where an angle changed), and the bearing change, which is of the order of the
//! tilt squared, is a short arctangent series.

use super::sweep::{Sweep, SweepMotion};
use super::{AngularOrder, Scan};

/// Which returns count as the floor. A hit is dropped when its height above the floor,
/// worked out from the estimated tilt and height, is below `height_tolerance_m +
/// range * tilt_tolerance_rad`: a floor return computes near zero, off by the height error plus
/// the range times the tilt error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorReturns {
    /// Error allowed in the scan plane's height, m: the estimate's height error (centimetres
    /// with the sonar); the lidar's mounting above the estimated point (8 cm on the simulated
    /// F450) only makes the test stricter, so it is left out.
    pub height_tolerance_m: f32,
    /// Error allowed in the estimated tilt, rad. In the simulator's gust storm the tilt
    /// estimate is 0.7 degrees off (RMS, 2-3 at worst), against 0.25 in still air. It costs
    /// real walls: a wall's foot closer to the floor than the tolerance is dropped too, which
    /// a tilted vehicle flying low sees at a few metres. Both sides bind near 0.04 rad: at
    /// 0.05 an exploration flight at exploring height lost enough wall feet for its estimate
    /// to go invalid, at 0.03 enough floor got through in the storm to put one seed's estimate
    /// 0.9 m off. A tolerance from the attitude estimate's own variance would serve both.
    pub tilt_tolerance_rad: f32,
    /// Below this height (m) a wall's foot and the floor cannot be told apart at the tolerances
    /// above, so no return is dropped: on the ground and early in a climb the scan is kept whole.
    pub min_height_m: f32,
}

impl Default for FloorReturns {
    fn default() -> Self {
        Self {
            height_tolerance_m: 0.15,
            tilt_tolerance_rad: 0.04,
            min_height_m: 0.5,
        }
    }
}

/// The vehicle's attitude and height when the scan was taken, as estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPlane {
    pub roll_rad: f32,
    pub pitch_rad: f32,
    /// Height of the scan plane above the floor, m; non-finite when unknown (no floor test).
    pub height_m: f32,
}

impl ScanPlane {
    /// Level, height unknown.
    pub const LEVEL: Self = Self {
        roll_rad: 0.0,
        pitch_rad: 0.0,
        height_m: f32::NAN,
    };
}

/// The levelled copy of the scan being matched, and the beam directions it was made with.
#[derive(Clone, Debug)]
pub struct Leveller<const N: usize> {
    pub floor: FloorReturns,
    /// Returns dropped as the floor so far.
    floor_dropped: u32,
    level: Scan<N>,
    /// Beam angle k of the last scan and its (sine, cosine); NaN before first use.
    angles: [f32; N],
    sin_cos: [(f32, f32); N],
}

impl<const N: usize> Default for Leveller<N> {
    fn default() -> Self {
        Self {
            floor: FloorReturns::default(),
            floor_dropped: 0,
            level: Scan::new(0.0),
            angles: [f32::NAN; N],
            sin_cos: [(0.0, 1.0); N],
        }
    }
}

impl<const N: usize> Leveller<N> {
    /// Returns dropped as the floor so far.
    pub fn floor_dropped(&self) -> u32 {
        self.floor_dropped
    }

    /// Levels `scan` taken from `plane` (non-finite tilts count as level), drops its floor
    /// returns, de-skews it for `motion` when its beams carry their times, and returns the
    /// result. Invalid beams are copied unchanged.
    pub fn level(&mut self, scan: &Scan<N>, plane: ScanPlane, motion: SweepMotion) -> &Scan<N> {
        let finite_or_level = |a: f32| if a.is_finite() { a } else { 0.0 };
        let (sr, cr) = libm::sincosf(finite_or_level(plane.roll_rad));
        let (sp, cp) = libm::sincosf(finite_or_level(plane.pitch_rad));
        // A hit at range r along a beam of world-vertical component dz is dropped when
        // h + r dz < tol_h + r tol_tilt, i.e. r (tol_tilt - dz) > h - tol_h.
        let floor = self.floor;
        let clearance_m = plane.height_m - floor.height_tolerance_m;
        let floor_test = plane.height_m >= floor.min_height_m && clearance_m > 0.0;
        // Beam times need not rise with the index (the XV-11 sweeps clockwise from a point
        // mid-scan), so the revolution's span is taken over all of them.
        let (first_s, last_s) = scan
            .beams()
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), b| {
                (lo.min(b.time_offset_s), hi.max(b.time_offset_s))
            });
        let sweep = Sweep::new(motion, first_s, last_s);
        self.level.clear(scan.stamp_s);
        let mut order = AngularOrder::default();
        for (k, beam) in scan.beams().iter().enumerate() {
            let mut b = *beam;
            if b.valid {
                if self.angles[k] != b.angle_rad {
                    self.angles[k] = b.angle_rad;
                    self.sin_cos[k] = libm::sincosf(b.angle_rad);
                }
                let (sa, ca) = self.sin_cos[k];
                let dz = cp * sr * sa - sp * ca;
                if floor_test && b.range_m * (floor.tilt_tolerance_rad - dz) > clearance_m {
                    b.valid = false;
                    self.floor_dropped = self.floor_dropped.saturating_add(1);
                    let _ = self.level.push(b);
                    continue;
                }
                // The hit rotated into the world, horizontal part, then taken to
                // mid-revolution; range and bearing once, from the final point.
                let hit = (b.range_m * (ca * cp + sa * sr * sp), b.range_m * (sa * cr));
                let (x, y) = match &sweep {
                    Some(sweep) => sweep.seen_from_mid(hit, b.time_offset_s),
                    None => hit,
                };
                b.range_m = libm::sqrtf(x * x + y * y);
                b.angle_rad += turn_between(ca * x + sa * y, ca * y - sa * x);
                // De-skewing moves a near hit further in bearing than a far one beside it,
                // and the first and last beams apart by the whole turn's motion: a beam that
                // falls behind the one before it (hidden, seen from mid-revolution) or past a
                // full turn (seen again) is dropped, or the matcher would refuse the scan.
                b.valid = order.admits(b.angle_rad);
            }
            // `level` has the input's capacity, so this cannot fail.
            let _ = self.level.push(b);
        }
        &self.level
    }
}

/// The angle from a direction to another, given their dot and cross products (any common
/// scale): a series where the angle is small, as levelling's always is below steep tilts.
/// Inlined: it runs on every beam.
#[inline]
pub(crate) fn turn_between(dot: f32, cross: f32) -> f32 {
    // Below 1/8 the series' first omitted term, q^9 / 9, is under 2e-9 rad.
    if dot > 0.0 && libm::fabsf(cross) <= 0.125 * dot {
        let q = cross / dot;
        let q2 = q * q;
        q * (1.0 - q2 * (1.0 / 3.0 - q2 * (1.0 / 5.0 - q2 * (1.0 / 7.0))))
    } else {
        libm::atan2f(cross, dot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::normalize_angle;
    use crate::scan::Beam;
    use core::f32::consts::FRAC_PI_2;
    use libm::{atan2f, cosf, sinf};

    /// A plane at `roll`, `pitch` with its height unknown (no floor test).
    fn tilted_plane(roll_rad: f32, pitch_rad: f32) -> ScanPlane {
        ScanPlane {
            roll_rad,
            pitch_rad,
            ..ScanPlane::LEVEL
        }
    }

    #[test]
    fn levelling_undoes_the_tilt_of_the_scan_plane() {
        let (roll, pitch) = (0.1f32, -0.2f32);
        // A wall 2 m ahead, seen level and seen tilted: the tilted plane meets it at 2/cos.
        let mut tilted = Scan::<360>::new(0.0);
        tilted.push(Beam::new(0.0, 2.0 / cosf(pitch))).unwrap();
        tilted.push(Beam::new(FRAC_PI_2, 1.5 / cosf(roll))).unwrap();
        tilted.push(Beam::invalid(3.0)).unwrap();
        let mut leveller = Leveller::default();
        let b = leveller
            .level(&tilted, tilted_plane(roll, pitch), SweepMotion::default())
            .beams();
        assert!(
            (b[0].range_m - 2.0).abs() < 1e-4 && b[0].angle_rad.abs() < 1e-5,
            "{:?}",
            b[0]
        );
        assert!((b[1].range_m - 1.5).abs() < 0.02, "{:?}", b[1]);
        assert!(!b[2].valid && b[2].angle_rad == 3.0);
    }

    /// The hit rotated by roll and pitch with library trigonometry: (range, bearing).
    fn rotated(angle: f32, range: f32, roll: f32, pitch: f32) -> (f32, f32) {
        let (px, py) = (range * cosf(angle), range * sinf(angle));
        let x = px * cosf(pitch) + py * sinf(roll) * sinf(pitch);
        let y = py * cosf(roll);
        (libm::hypotf(x, y), atan2f(y, x))
    }

    #[test]
    fn agrees_with_the_rotation_at_every_bearing_and_tilt() {
        let mut leveller = Leveller::<720>::default();
        for (roll, pitch) in [
            (0.0, 0.0),
            (0.02, -0.01),
            (0.2, 0.1),
            (-0.35, 0.35),
            (0.6, -0.5),
        ] {
            let mut scan = Scan::<720>::new(1.0);
            for k in 0..720 {
                // Bearings over more than a turn, as some devices report them.
                let angle = -3.5 + k as f32 * 0.01;
                scan.push(Beam::new(angle, 1.0 + (k % 7) as f32)).unwrap();
            }
            let out = leveller.level(&scan, tilted_plane(roll, pitch), SweepMotion::default());
            assert_eq!(out.stamp_s, 1.0);
            for (b, a) in out.beams().iter().zip(scan.beams()) {
                let (range, bearing) = rotated(a.angle_rad, a.range_m, roll, pitch);
                assert!((b.range_m - range).abs() < 2e-6 * range, "{b:?} vs {range}");
                // Same bearing, and continuous with the original one.
                assert!(normalize_angle(b.angle_rad - bearing).abs() < 2e-6, "{b:?}");
                assert!((b.angle_rad - a.angle_rad).abs() < 0.5, "{b:?} from {a:?}");
            }
        }
    }

    #[test]
    fn a_changed_beam_angle_is_not_levelled_with_the_old_direction() {
        let mut leveller = Leveller::<4>::default();
        let (roll, pitch) = (0.3, 0.2);
        for angle in [0.5f32, 2.0] {
            let mut scan = Scan::<4>::new(0.0);
            scan.push(Beam::new(angle, 3.0)).unwrap();
            let b = leveller
                .level(&scan, tilted_plane(roll, pitch), SweepMotion::default())
                .beams()[0];
            let (range, bearing) = rotated(angle, 3.0, roll, pitch);
            assert!((b.range_m - range).abs() < 1e-5 && (b.angle_rad - bearing).abs() < 1e-5);
        }
    }

    #[test]
    fn a_non_finite_tilt_counts_as_level() {
        let mut leveller = Leveller::<4>::default();
        let mut scan = Scan::<4>::new(0.0);
        scan.push(Beam::new(0.7, 2.5)).unwrap();
        let b = leveller
            .level(
                &scan,
                tilted_plane(f32::NAN, f32::INFINITY),
                SweepMotion::default(),
            )
            .beams()[0];
        assert!((b.range_m - 2.5).abs() < 1e-6 && (b.angle_rad - 0.7).abs() < 1e-6);
    }

    /// A 1 m high plane pitched 15 degrees nose down: the beam ahead meets the floor at
    /// 1 / sin(15°) = 3.86 m, the beam behind climbs; beams to the side stay level.
    #[test]
    fn floor_returns_are_dropped_and_walls_kept() {
        let pitch = 15f32.to_radians();
        let plane = ScanPlane {
            roll_rad: 0.0,
            pitch_rad: pitch,
            height_m: 1.0,
        };
        let mut scan = Scan::<8>::new(0.0);
        let floor_ahead = 1.0 / sinf(pitch);
        scan.push(Beam::new(0.0, floor_ahead)).unwrap();
        // A wall 2 m ahead: met 0.52 m below the plane, well above the floor.
        scan.push(Beam::new(0.0, 2.0 / cosf(pitch))).unwrap();
        // In bearing order, as a revolution comes (a beam out of order is dropped).
        scan.push(Beam::new(FRAC_PI_2, 6.0)).unwrap();
        scan.push(Beam::new(core::f32::consts::PI, 3.0)).unwrap();
        let mut leveller = Leveller::default();
        let b = leveller.level(&scan, plane, SweepMotion::default()).beams();
        assert!(!b[0].valid, "{:?}", b[0]);
        assert!(
            b[1].valid && (b[1].range_m - 2.0).abs() < 1e-4,
            "{:?}",
            b[1]
        );
        assert!(b[2].valid && b[3].valid);
        assert_eq!(leveller.floor_dropped(), 1);
        // The same scan from near the ground, or at an unknown height, is kept whole: there a
        // wall's foot and the floor look alike.
        for height_m in [0.3, f32::NAN] {
            let low = ScanPlane { height_m, ..plane };
            let mut leveller = Leveller::default();
            let b = leveller.level(&scan, low, SweepMotion::default()).beams();
            assert!(b.iter().all(|b| b.valid), "{height_m}");
            assert_eq!(leveller.floor_dropped(), 0);
        }
    }
}
