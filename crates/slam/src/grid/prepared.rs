//! A scan as beam end points in the sensor frame, computed once per keyframe: inserting it at a
//! pose then costs a rotation per beam and no trigonometry, which matters when a loop closure
//! moves every keyframe and the whole map is rebuilt.

use super::GridError;
use plumbline_core::geom::Vec2;
use plumbline_core::scan::Beam;

/// End points of one scan in the sensor frame: `hits` end in an obstacle (their last cell
/// becomes more occupied), `clears` only mark free space up to their end.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreparedScan {
    hits: Vec<Vec2>,
    clears: Vec<Vec2>,
}

impl PreparedScan {
    pub fn new() -> Self {
        Self::default()
    }

    /// Applies the range rules to a device's beams:
    /// - a valid beam within `max_range_m` is a hit at its range;
    /// - a valid beam beyond `max_range_m` clears free space up to `max_range_m` and marks no
    ///   obstacle (the range the caller trusts; far returns are the noisiest and most often
    ///   mixed pixels);
    /// - an invalid beam ("no return") clears free space up to `no_return_clear_m` when that is
    ///   given, and is skipped otherwise. Skipping is the default ([`super::GridConfig`]) because
    ///   "no return" does not mean "nothing there": the simulated and real devices drop returns
    ///   on dark surfaces and at grazing incidence, and clearing along such a beam would erase
    ///   the very wall it missed. A device whose invalid flag reliably means "nothing within
    ///   range" (a long-range lidar in a hall) can opt in.
    pub fn from_beams(
        beams: &[Beam],
        max_range_m: f32,
        no_return_clear_m: Option<f32>,
    ) -> Result<Self, GridError> {
        if !(max_range_m.is_finite() && max_range_m > 0.0) {
            return Err(GridError::Config(format!(
                "max range {max_range_m} m must be finite and positive"
            )));
        }
        if let Some(d) = no_return_clear_m {
            if !(d.is_finite() && d > 0.0) {
                return Err(GridError::Config(format!(
                    "no-return clearing range {d} m must be finite and positive"
                )));
            }
        }
        let mut out = Self::new();
        for b in beams {
            let dir = || Vec2::new(b.angle_rad.cos(), b.angle_rad.sin());
            if b.valid && b.range_m.is_finite() && b.range_m > 0.0 {
                if b.range_m <= max_range_m {
                    out.push_hit(dir() * b.range_m);
                } else {
                    out.push_clear(dir() * max_range_m);
                }
            } else if let Some(d) = no_return_clear_m {
                out.push_clear(dir() * d.min(max_range_m));
            }
        }
        Ok(out)
    }

    /// Adds a beam that ended in an obstacle at `p` (sensor frame, m). Non-finite points are
    /// dropped and reported by the return value, so a caller can count them.
    pub fn push_hit(&mut self, p: Vec2) -> bool {
        p.is_finite() && {
            self.hits.push(p);
            true
        }
    }

    /// Adds a beam that saw free space up to `p` and nothing there.
    pub fn push_clear(&mut self, p: Vec2) -> bool {
        p.is_finite() && {
            self.clears.push(p);
            true
        }
    }

    pub fn hits(&self) -> &[Vec2] {
        &self.hits
    }

    pub fn clears(&self) -> &[Vec2] {
        &self.clears
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        (self.hits.capacity() + self.clears.capacity()) * core::mem::size_of::<Vec2>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_rules() {
        let beams = [
            Beam::new(0.0, 2.0),
            Beam::new(core::f32::consts::FRAC_PI_2, 9.0),
            Beam::invalid(core::f32::consts::PI),
            Beam {
                valid: true,
                ..Beam::new(0.1, f32::NAN)
            },
        ];
        let s = PreparedScan::from_beams(&beams, 4.0, None).unwrap();
        assert_eq!(s.hits().len(), 1);
        assert!((s.hits()[0] - Vec2::new(2.0, 0.0)).norm() < 1e-6);
        assert_eq!(s.clears().len(), 1, "beyond max range clears to max range");
        assert!((s.clears()[0] - Vec2::new(0.0, 4.0)).norm() < 1e-6);
        let s = PreparedScan::from_beams(&beams, 4.0, Some(1.5)).unwrap();
        assert_eq!(s.clears().len(), 3, "no-return beams clear when asked");
        assert!((s.clears()[1] - Vec2::new(-1.5, 0.0)).norm() < 1e-6);
        assert!(PreparedScan::from_beams(&beams, f32::NAN, None).is_err());
        assert!(PreparedScan::from_beams(&beams, 4.0, Some(-1.0)).is_err());
        let mut s = PreparedScan::new();
        assert!(!s.push_hit(Vec2::new(f32::INFINITY, 0.0)));
        assert!(s.hits().is_empty());
    }
}
