//! One lidar revolution in Plumbline's convention.
//!
//! Angles are counter-clockwise from body x (radians); every beam carries its own validity so a
//! device's "no return" is never confused with a range of 0 or max. Each beam also carries the
//! time since the revolution started, so motion during the sweep can be removed later.
//!
//! Preprocessing that turns a revolution as the sensor took it into one the matcher can use
//! lives beside it: [`level`] projects a tilted scan onto the horizontal plane and [`sweep`]
//! moves every beam to where the sensor was at mid-revolution.

pub mod level;
pub mod sweep;

use crate::geom::Vec2;
use libm::{cosf, sinf};

/// One beam of a revolution.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Beam {
    pub angle_rad: f32,
    pub range_m: f32,
    /// Seconds after the first beam of the revolution.
    pub time_offset_s: f32,
    /// False for "no return", max-range sentinels, device-flagged and non-finite readings.
    pub valid: bool,
}

impl Beam {
    /// A beam that is valid only when its range is finite and strictly positive.
    pub fn new(angle_rad: f32, range_m: f32) -> Self {
        Self {
            angle_rad,
            range_m,
            time_offset_s: 0.0,
            valid: range_m.is_finite() && range_m > 0.0,
        }
    }

    pub fn invalid(angle_rad: f32) -> Self {
        Self {
            angle_rad,
            range_m: 0.0,
            time_offset_s: 0.0,
            valid: false,
        }
    }

    /// The hit point in the sensor frame.
    pub fn point(&self) -> Vec2 {
        Vec2::new(
            self.range_m * cosf(self.angle_rad),
            self.range_m * sinf(self.angle_rad),
        )
    }
}

/// The order the matcher needs of a revolution's valid beams (`matching::prepared`): each
/// bearing, measured from the first valid beam's, at least the one before and at most a turn
/// (and a milliradian). Fed the beams one by one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AngularOrder {
    first: Option<f32>,
    previous: f32,
}

impl Default for AngularOrder {
    fn default() -> Self {
        Self {
            first: None,
            previous: f32::NEG_INFINITY,
        }
    }
}

impl AngularOrder {
    /// Whether a valid beam at `angle_rad` keeps the order; if it does, it is the new last one.
    pub(crate) fn admits(&mut self, angle_rad: f32) -> bool {
        let bearing = angle_rad - *self.first.get_or_insert(angle_rad);
        let in_order = bearing >= self.previous && bearing <= core::f32::consts::TAU + 1e-3;
        if in_order {
            self.previous = bearing;
        }
        in_order
    }
}

/// Returned when a scan already holds `N` beams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanFull {
    pub capacity: usize,
}

/// A revolution of at most `N` beams, stored inline (no heap).
#[derive(Clone, Debug)]
pub struct Scan<const N: usize> {
    /// Time of the first beam, seconds (device or log clock).
    pub stamp_s: f64,
    beams: [Beam; N],
    len: usize,
}

impl<const N: usize> Default for Scan<N> {
    fn default() -> Self {
        Self::new(0.0)
    }
}

impl<const N: usize> Scan<N> {
    pub const CAPACITY: usize = N;

    pub fn new(stamp_s: f64) -> Self {
        Self {
            stamp_s,
            beams: [Beam::default(); N],
            len: 0,
        }
    }

    pub fn clear(&mut self, stamp_s: f64) {
        self.stamp_s = stamp_s;
        self.len = 0;
    }

    pub fn push(&mut self, beam: Beam) -> Result<(), ScanFull> {
        let slot = self
            .beams
            .get_mut(self.len)
            .ok_or(ScanFull { capacity: N })?;
        *slot = beam;
        self.len += 1;
        Ok(())
    }

    pub fn beams(&self) -> &[Beam] {
        &self.beams[..self.len]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn valid_count(&self) -> usize {
        self.beams().iter().filter(|b| b.valid).count()
    }

    /// Builds a scan of equally spaced beams; invalid readings are flagged by `is_valid`.
    pub fn from_ranges(
        stamp_s: f64,
        start_angle_rad: f32,
        increment_rad: f32,
        ranges_m: &[f32],
        is_valid: impl Fn(f32) -> bool,
    ) -> Result<Self, ScanFull> {
        let mut scan = Self::new(stamp_s);
        for (i, &r) in ranges_m.iter().enumerate() {
            let angle = start_angle_rad + increment_rad * i as f32;
            let ok = r.is_finite() && r > 0.0 && is_valid(r);
            let beam = if ok {
                Beam::new(angle, r)
            } else {
                Beam::invalid(angle)
            };
            scan.push(beam)?;
        }
        Ok(scan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_past_capacity_is_an_error_not_a_panic() {
        let mut s: Scan<2> = Scan::new(0.0);
        assert!(s.push(Beam::new(0.0, 1.0)).is_ok());
        assert!(s.push(Beam::new(0.1, 1.0)).is_ok());
        assert_eq!(s.push(Beam::new(0.2, 1.0)), Err(ScanFull { capacity: 2 }));
        assert_eq!(s.len(), 2);
    }

    #[test]
    fn non_finite_zero_and_rejected_ranges_are_invalid() {
        let ranges = [1.0, f32::NAN, 0.0, f32::INFINITY, -1.0, 81.83];
        let s: Scan<8> = Scan::from_ranges(0.0, 0.0, 0.1, &ranges, |r| r < 80.0).unwrap();
        let valid: [bool; 6] = core::array::from_fn(|i| s.beams()[i].valid);
        assert_eq!(valid, [true, false, false, false, false, false]);
        assert_eq!(s.valid_count(), 1);
    }

    #[test]
    fn beam_point_is_counter_clockwise_from_x() {
        let p = Beam::new(core::f32::consts::FRAC_PI_2, 2.0).point();
        assert!(p.x.abs() < 1e-6 && (p.y - 2.0).abs() < 1e-6);
    }
}
