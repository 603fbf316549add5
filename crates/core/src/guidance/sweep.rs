//! One revolution laid out once per step in the order the rules read it: counter-clockwise
//! from `rule_start_rad` (seed 002's "beginning of the scan on the right"), with each beam's
//! direction and hit computed once, since segments, gaps, field and guard all visit every beam.

use crate::fast_math::sin_cos;
use crate::geom::{normalize_angle, Vec2};
use crate::scan::{Beam, Scan};
use core::f32::consts::TAU;

/// The beams of one scan in sweep order, on the stack (17 bytes a beam: 6.1 KB for 360).
pub struct Sweep<const N: usize> {
    unit: [Vec2; N],
    range_m: [f32; N],
    rel_rad: [f32; N],
    usable: [bool; N],
    len: usize,
    start: usize,
    ordered: bool,
}

impl<const N: usize> Sweep<N> {
    pub fn new(scan: &Scan<N>, start_rad: f32) -> Self {
        let beams = scan.beams();
        let start = sweep_start(beams, start_rad);
        let mut s = Self {
            unit: [Vec2::ZERO; N],
            range_m: [0.0; N],
            rel_rad: [0.0; N],
            usable: [false; N],
            len: beams.len(),
            start,
            ordered: true,
        };
        for pos in 0..s.len {
            let b = &beams[(start + pos) % s.len];
            s.usable[pos] = usable(b);
            if b.angle_rad.is_finite() {
                // Wrapped first: the fast sine is accurate within a turn.
                let (sin, cos) = sin_cos(normalize_angle(b.angle_rad));
                s.unit[pos] = Vec2::new(cos, sin);
                s.rel_rad[pos] = relative_angle(b.angle_rad, start_rad);
            }
            s.range_m[pos] = b.range_m;
            s.ordered &=
                b.angle_rad.is_finite() && (pos == 0 || s.rel_rad[pos] > s.rel_rad[pos - 1]);
        }
        s
    }

    /// True when every angle is finite and the angles grow along the sweep (every real lidar
    /// revolution): searches may stop early.
    pub fn is_ordered(&self) -> bool {
        self.ordered
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// Index into `scan.beams()` of sweep position `pos`.
    pub fn beam_index(&self, pos: usize) -> usize {
        (self.start + pos) % self.len.max(1)
    }

    pub fn is_usable(&self, pos: usize) -> bool {
        self.usable[pos]
    }

    /// Unit vector along beam `pos`, sensor frame.
    pub fn unit(&self, pos: usize) -> Vec2 {
        self.unit[pos]
    }

    /// Measured range of beam `pos`, m (meaningful only when usable).
    pub fn range_m(&self, pos: usize) -> f32 {
        self.range_m[pos]
    }

    /// Angle of beam `pos` counter-clockwise from the sweep start, rad in [0, 2π).
    pub fn rel_rad(&self, pos: usize) -> f32 {
        self.rel_rad[pos]
    }

    /// The hit of beam `pos` in the sensor frame (meaningful only when usable).
    pub fn point(&self, pos: usize) -> Vec2 {
        self.unit[pos] * self.range_m[pos]
    }

    pub fn hit(&self, pos: usize) -> Option<Vec2> {
        self.usable[pos].then(|| self.point(pos))
    }
}

/// A beam whose hit can be used: flagged valid and with a finite positive range and angle.
pub fn usable(b: &Beam) -> bool {
    b.valid && b.range_m.is_finite() && b.range_m > 0.0 && b.angle_rad.is_finite()
}

/// Angle counter-clockwise from `start`, in [0, 2π).
pub fn relative_angle(angle_rad: f32, start_rad: f32) -> f32 {
    // Beam angles are within a turn of the start: one correction, no division, as a rule.
    let d = angle_rad - start_rad;
    if (0.0..TAU).contains(&d) {
        return d;
    }
    if (0.0..TAU).contains(&(d + TAU)) {
        return d + TAU;
    }
    let r = libm::fmodf(d, TAU);
    let r = if r < 0.0 { r + TAU } else { r };
    // Rounding can land a tiny negative remainder exactly on 2π.
    if r >= TAU {
        0.0
    } else {
        r
    }
}

/// The beam first counter-clockwise from `start_rad`: where the sweep begins.
fn sweep_start(beams: &[Beam], start_rad: f32) -> usize {
    let mut best = (0, f32::INFINITY);
    for (i, b) in beams.iter().enumerate() {
        let rel = if b.angle_rad.is_finite() {
            relative_angle(b.angle_rad, start_rad)
        } else {
            f32::INFINITY
        };
        if rel < best.1 {
            best = (i, rel);
        }
    }
    best.0
}
