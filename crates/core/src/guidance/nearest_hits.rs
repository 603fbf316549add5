//! The nearest hit in each sector of one revolution: what the flight part keeps of a scan to
//! guard the setpoints it flies ([`super::guard`]).
//!
//! The flight part must check the command in the frame it flies it in, whatever frame the
//! companion guarded it in. It has the raw scan at every revolution but no room to keep one
//! (a URG-04LX revolution is 11 KB), so it keeps the nearest hit of each `SECTOR_RAD` sector
//! at its own bearing: 288 bytes. Against a flat wall the nearest hit is the foot of the
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
    /// Bearing (rad) and range (m) of the sector's nearest hit; range infinite without one.
    hits: [(f32, f32); SECTORS],
    /// The nearest of them all, m (infinite without a hit).
    nearest_m: f32,
}

impl Default for NearestHits {
    /// No hit anywhere.
    fn default() -> Self {
        Self {
            hits: [(0.0, f32::INFINITY); SECTORS],
            nearest_m: f32::INFINITY,
        }
    }
}

impl NearestHits {
    /// The nearest usable hit of each sector of `scan`.
    pub fn of_scan<const N: usize>(scan: &Scan<N>) -> Self {
        let mut out = Self::default();
        for b in scan.beams().iter().filter(|b| usable(b)) {
            let turn = b.angle_rad / TAU;
            let wrapped = (turn - floorf(turn)) * TAU;
            let sector = ((wrapped / SECTOR_RAD) as usize).min(SECTORS - 1);
            let slot = &mut out.hits[sector];
            if b.range_m < slot.1 {
                *slot = (b.angle_rad, b.range_m);
            }
            out.nearest_m = out.nearest_m.min(b.range_m);
        }
        out
    }

    /// Range of the nearest hit, m (infinite without one): a command no faster than the
    /// allowance at this range respects every hit, and needs no closer look.
    pub fn nearest_m(&self) -> f32 {
        self.nearest_m
    }

    /// Unit direction (body frame) and range of each sector's nearest hit.
    pub fn iter(&self) -> impl Iterator<Item = (Vec2, f32)> + '_ {
        self.hits
            .iter()
            .filter(|(_, r)| r.is_finite())
            .map(|&(a, r)| (Vec2::new(cosf(a), sinf(a)), r))
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
        let hits: Vec<_> = NearestHits::of_scan(&scan).iter().collect();
        // 0.01 and 0.05 share the first sector; -0.05 wraps to the last one.
        assert_eq!(hits.len(), 3, "{hits:?}");
        assert!(hits
            .iter()
            .any(|(u, r)| *r == 1.5 && (u.y - sinf(0.05)).abs() < 1e-6));
        assert!(hits.iter().any(|(u, r)| *r == 1.0 && u.y < 0.0));
        assert!(hits.iter().any(|(_, r)| *r == 4.0));
        assert_eq!(NearestHits::of_scan(&scan).nearest_m(), 1.0);
    }
}
