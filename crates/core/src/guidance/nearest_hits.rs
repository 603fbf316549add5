//! The nearest hit in each sector of one revolution: what the flight part keeps of a scan to
//! guard the setpoints it flies ([`super::guard`]).
//!
//! The flight part must check the command in the frame it flies it in, whatever frame the
//! companion guarded it in. It has the raw scan at every revolution but no room to keep one
//! (a URG-04LX revolution is 11 KB), so it keeps the nearest hit of each `SECTOR_RAD` sector
//! at its own bearing: 432 bytes, the bearing kept as a unit vector so that the guard, which
//! runs at every step, does no trigonometry. Against a flat wall the nearest hit is the foot of the
//! perpendicular, the hit that binds the speed toward the wall; the hits left out only bind
//! the speed along the wall close to it, which the companion's guard limits on the full scan.

use super::sweep::usable;
use crate::geom::Vec2;
use crate::scan::Scan;
use core::f32::consts::TAU;
use libm::{cosf, floorf, sinf};

/// Sectors a revolution is divided into (10 degrees each).
pub const SECTORS: usize = 36;
const SECTOR_RAD: f32 = TAU / SECTORS as f32;

/// The nearest usable hit of each sector of a revolution (body frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearestHits {
    /// Unit direction and range (m) of each sector's nearest hit, nearest first; range
    /// infinite for sectors without one. Sorted once a revolution so that a step looks only at
    /// the few hits near enough to bind its command.
    hits: [(Vec2, f32); SECTORS],
}

impl Default for NearestHits {
    /// No hit anywhere.
    fn default() -> Self {
        Self {
            hits: [(Vec2::ZERO, f32::INFINITY); SECTORS],
        }
    }
}

impl NearestHits {
    /// The nearest usable hit of each sector of `scan`.
    pub fn of_scan<const N: usize>(scan: &Scan<N>) -> Self {
        let mut bearings = [0.0f32; SECTORS];
        let mut out = Self::default();
        for b in scan.beams().iter().filter(|b| usable(b)) {
            let turn = b.angle_rad / TAU;
            let wrapped = (turn - floorf(turn)) * TAU;
            let sector = ((wrapped / SECTOR_RAD) as usize).min(SECTORS - 1);
            if b.range_m < out.hits[sector].1 {
                out.hits[sector].1 = b.range_m;
                bearings[sector] = b.angle_rad;
            }
        }
        for (hit, bearing) in out.hits.iter_mut().zip(bearings) {
            hit.0 = Vec2::new(cosf(bearing), sinf(bearing));
        }
        out.hits.sort_unstable_by(|a, b| a.1.total_cmp(&b.1));
        out
    }

    /// Unit direction (body frame) and range of each sector's nearest hit closer than
    /// `range_m`, nearest first.
    pub fn closer_than(&self, range_m: f32) -> impl Iterator<Item = (Vec2, f32)> + '_ {
        self.hits.iter().take_while(move |h| h.1 < range_m).copied()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::scan::Beam;
    use std::vec::Vec;

    #[test]
    fn each_sector_keeps_its_nearest_hit_at_its_own_bearing() {
        let mut scan: Scan<8> = Scan::new(0.0);
        for (angle, range) in [(0.01, 2.0), (0.05, 1.5), (-0.05, 1.0), (3.0, 4.0)] {
            scan.push(Beam::new(angle, range)).unwrap();
        }
        scan.push(Beam::invalid(0.02)).unwrap();
        let hits: Vec<_> = NearestHits::of_scan(&scan)
            .closer_than(f32::INFINITY)
            .collect();
        // 0.01 and 0.05 share the first sector; -0.05 wraps to the last one.
        assert_eq!(hits.len(), 3, "{hits:?}");
        assert!(hits
            .iter()
            .any(|(u, r)| *r == 1.5 && (u.y - sinf(0.05)).abs() < 1e-6));
        assert!(hits.iter().any(|(u, r)| *r == 1.0 && u.y < 0.0));
        assert!(hits.iter().any(|(_, r)| *r == 4.0));
        let near: Vec<_> = NearestHits::of_scan(&scan).closer_than(1.6).collect();
        assert_eq!(near.iter().map(|h| h.1).collect::<Vec<_>>(), [1.0, 1.5]);
    }
}
