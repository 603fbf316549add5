//! Seed 002's velocity field, eqs. 1-2: every beam adds a unit vector, turned according to its
//! range, weighted by the inverse of its distance beyond `r_min`, and averaged over the beams.
//!
//! The seed's body frame is NED-like (angles clockwise); here angles are counter-clockwise
//! (REP 103), so eq. 1 is mirrored: `γ = θ + π − (π/2)·r/r_goal` for `r ≤ 2 r_goal` and `γ = θ`
//! beyond. A hit at `r_goal` on the right (θ = −π/2) then pushes straight ahead, a nearer hit
//! pushes away from it and a farther one pulls toward it: right-hand wall following.
//!
//! Narrow gaps are flown past "with no effect on the commanded velocity" (seed 002, Fig. 5):
//! beams through a gap narrower than `min_gap_width_m` are read as hitting the straight wall
//! across the gap, so an opening the vehicle cannot use never pulls it in.

use super::config::GuidanceConfig;
use super::prls::WallSegments;
use super::sweep::Sweep;
use crate::fast_math::sin_cos;
use crate::geom::Vec2;
use core::f32::consts::{FRAC_PI_2, PI};

/// Which part of the field is summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldPart {
    /// Eq. 1 as the seed states it: wall following, attraction to open space, repulsion.
    WallFollow,
    /// Only the component of eq. 1 pointing away from hits nearer than `r_goal`: keeps
    /// clearance while something else (a waypoint) sets the direction.
    Repulsive,
}

/// The field's output for one revolution, sensor frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSum {
    /// `K_v / n · Σ (cos γ_i, sin γ_i) / |r_i − r_min|`, m/s (eq. 2), before any speed limit.
    pub velocity_m_s: Vec2,
    /// The gain used: `K_v` raised as the nearest range approaches `r_min`, m²/s.
    pub gain_m2_s: f32,
    /// Nearest valid range (virtual walls across narrow gaps included), m.
    pub nearest_range_m: f32,
    /// Beams in the average (`n` of eq. 2).
    pub beams: usize,
    /// Narrow openings read as wall: gaps under `min_gap_width_m` that some beam looked through.
    pub narrow_gaps: usize,
}

/// Sums the field over the sweep; `None` when no beam is usable.
pub(super) fn field_sum<const N: usize, const S: usize>(
    sweep: &Sweep<N>,
    walls: &WallSegments<S>,
    cfg: &GuidanceConfig,
    part: FieldPart,
) -> Option<FieldSum> {
    let mut sum = Vec2::ZERO;
    let mut n = 0usize;
    let mut nearest = f32::INFINITY;
    let narrow_gaps = for_each_effective_beam(sweep, walls, cfg, |ray, range| {
        let w = 1.0 / (range - cfg.r_min_m()).abs().max(cfg.weight_floor_m);
        let push = match part {
            // γ − θ of eq. 1, applied as a rotation of the beam's own direction.
            FieldPart::WallFollow => rotate(ray, increment_angle(0.0, range, cfg.r_goal_m)),
            FieldPart::Repulsive if range < cfg.r_goal_m => {
                ray * -sin_cos(FRAC_PI_2 * range / cfg.r_goal_m).1
            }
            FieldPart::Repulsive => Vec2::ZERO,
        };
        sum = sum + push * w;
        n += 1;
        nearest = nearest.min(range);
    });
    if n == 0 {
        return None;
    }
    let gain = boosted_gain(nearest, cfg);
    Some(FieldSum {
        velocity_m_s: sum * (gain / n as f32),
        gain_m2_s: gain,
        nearest_range_m: nearest,
        beams: n,
        narrow_gaps,
    })
}

/// Seed 002 eq. 1 in counter-clockwise angles: the direction of one beam's increment.
pub fn increment_angle(beam_rad: f32, range_m: f32, r_goal_m: f32) -> f32 {
    if range_m <= 2.0 * r_goal_m {
        beam_rad + PI - FRAC_PI_2 * range_m / r_goal_m
    } else {
        beam_rad
    }
}

/// `K_v` raised linearly from 1× at `r_goal` to `(1 + boost)×` at `r_min` and nearer.
pub fn boosted_gain(nearest_m: f32, cfg: &GuidanceConfig) -> f32 {
    let span = cfg.r_goal_m - cfg.r_min_m();
    let closeness = ((cfg.r_goal_m - nearest_m) / span).clamp(0.0, 1.0);
    cfg.k_v_m2_s * (1.0 + cfg.k_v_boost * closeness)
}

/// Calls `f(direction, range)` for every usable beam, and for every beam inside a gap
/// narrower than `min_gap_width_m` with the range to the chord across the gap where that is
/// nearer. Returns how many narrow gaps shortened at least one beam (openings flown past).
fn for_each_effective_beam<const N: usize, const S: usize>(
    sweep: &Sweep<N>,
    walls: &WallSegments<S>,
    cfg: &GuidanceConfig,
    mut f: impl FnMut(Vec2, f32),
) -> usize {
    let mut narrow = [None; S];
    let mut narrow_len = 0;
    for g in walls
        .gaps()
        .iter()
        .filter(|g| g.width_m < cfg.min_gap_width_m)
    {
        narrow[narrow_len] = Some(g);
        narrow_len += 1;
    }
    let narrow = &narrow[..narrow_len];
    let mut used = [false; S];
    for pos in 0..sweep.len() {
        let ray = sweep.unit(pos);
        let mut range = if sweep.is_usable(pos) {
            sweep.range_m(pos)
        } else {
            f32::INFINITY
        };
        for g in narrow.iter().flatten() {
            if g.spans(pos) {
                let [a, b] = g.narrowest_m;
                if let Some(chord) = ray_hits_chord(ray, a, b) {
                    if chord < range - cfg.line_tolerance_m {
                        used[g.after] = true;
                    }
                    range = range.min(chord);
                }
            }
        }
        if range.is_finite() && ray != Vec2::ZERO {
            f(ray, range);
        }
    }
    used.iter().filter(|&&u| u).count()
}

fn rotate(v: Vec2, angle_rad: f32) -> Vec2 {
    let (s, c) = sin_cos(angle_rad);
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Range along the unit ray `dir` from the sensor to the segment `a`-`b`, if it crosses it.
fn ray_hits_chord(dir: Vec2, a: Vec2, b: Vec2) -> Option<f32> {
    let e = b - a;
    let denom = dir.cross(e);
    if denom.abs() < 1e-9 {
        return None;
    }
    let t = a.cross(e) / denom;
    let u = a.cross(dir) / denom;
    (t > 0.0 && (-1e-3..=1.0 + 1e-3).contains(&u)).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::{Beam, Scan};
    use core::f32::consts::FRAC_PI_2;

    fn close(a: f32, b: f32) -> bool {
        (crate::geom::normalize_angle(a - b)).abs() < 1e-5
    }

    #[test]
    fn eq1_turns_each_beam_by_its_range() {
        let rg = 1.2;
        // A hit at r_goal on the right pushes straight ahead; on the left, straight back.
        assert!(close(increment_angle(-FRAC_PI_2, rg, rg), 0.0));
        assert!(close(increment_angle(FRAC_PI_2, rg, rg), PI));
        // Touching: straight away from the hit. At 2 r_goal and beyond: toward it (no jump).
        assert!(close(increment_angle(0.3, 0.0, rg), 0.3 + PI));
        assert!(close(increment_angle(0.3, 2.0 * rg, rg), 0.3));
        assert!(close(increment_angle(0.3, 5.0, rg), 0.3));
    }

    #[test]
    fn the_gain_rises_from_r_goal_to_r_min() {
        let cfg = GuidanceConfig::default();
        let k = cfg.k_v_m2_s;
        assert_eq!(boosted_gain(3.0, &cfg), k);
        assert_eq!(boosted_gain(cfg.r_goal_m, &cfg), k);
        assert!((boosted_gain(cfg.r_min_m(), &cfg) - 3.0 * k).abs() < 1e-5);
        assert!((boosted_gain(0.5 * (cfg.r_goal_m + cfg.r_min_m()), &cfg) - 2.0 * k).abs() < 1e-4);
        assert!((boosted_gain(0.1, &cfg) - 3.0 * k).abs() < 1e-5);
    }

    #[test]
    fn eq2_on_one_beam_is_k_v_over_the_distance_beyond_r_min() {
        let cfg = GuidanceConfig::default();
        let mut scan: Scan<4> = Scan::new(0.0);
        scan.push(Beam::new(-FRAC_PI_2, cfg.r_goal_m)).unwrap();
        scan.push(Beam::invalid(0.0)).unwrap();
        let sweep = Sweep::new(&scan, cfg.rule_start_rad);
        let walls = WallSegments::<4>::default();
        let f = field_sum(&sweep, &walls, &cfg, FieldPart::WallFollow).unwrap();
        let expected = cfg.k_v_m2_s / (cfg.r_goal_m - cfg.r_min_m());
        assert_eq!(f.beams, 1);
        assert!((f.velocity_m_s.x - expected).abs() < 1e-4, "{f:?}");
        assert!(f.velocity_m_s.y.abs() < 1e-4, "{f:?}");
        // The repulsive part of a hit at r_goal is nil; nearer, it points away from the hit.
        let r = field_sum(&sweep, &walls, &cfg, FieldPart::Repulsive).unwrap();
        assert!(r.velocity_m_s.norm() < 1e-5, "{r:?}");
        let mut near: Scan<4> = Scan::new(0.0);
        near.push(Beam::new(-FRAC_PI_2, 0.7)).unwrap();
        let sweep = Sweep::new(&near, cfg.rule_start_rad);
        let r = field_sum(&sweep, &walls, &cfg, FieldPart::Repulsive).unwrap();
        assert!(
            r.velocity_m_s.y > 0.5 && r.velocity_m_s.x.abs() < 1e-4,
            "{r:?}"
        );
    }
}
