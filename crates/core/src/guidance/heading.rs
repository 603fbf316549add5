//! Seed 002's heading rules: align with the farthest contiguous wall segment, going
//! counter-clockwise from the start of the scan on the right until a gap wide enough to fly
//! through; and the corridor test (free width under twice `r_goal`: keep equal distance to
//! both sides).
//!
//! "Right" and "backwards" are taken about body x, except after a turn-around (a dead end, or
//! the far side of a corridor's end past a door): the seed's vehicle turns its body around
//! there, and the rules then look down the way back. Until the body has turned (for ever, for a
//! vehicle that does not turn because its lidar sees all round) they look from the turned
//! heading instead; from body x they would keep seeing the end ahead, and flip between it and
//! the way out at every revolution (see `Guidance::step`).

use super::config::GuidanceConfig;
use super::prls::WallSegments;
use super::sweep::Sweep;
use crate::geom::{normalize_angle, Vec2};
use core::f32::consts::FRAC_PI_2;

/// What the heading rules concluded from the segments in the rules' window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HeadingRule {
    /// No segment starts inside the window: the heading is held.
    NoWall,
    /// Align with `segment`; the chain of walls stopped at `gap` (index into `gaps()`), the first
    /// gap wide enough, or at the last segment in the window (`None`).
    FollowWall { segment: usize, gap: Option<usize> },
    /// No gap wide enough in the window and the farthest wall points backwards: the vehicle
    /// turns around (a dead end, or a room with no usable exit on this side).
    DeadEnd { segment: usize },
}

/// The rules' choice: which way to point, relative to the sensor's x axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadingChoice {
    pub rule: HeadingRule,
    /// Heading to take, rad relative to body x; `None` keeps the current one.
    pub body_rad: Option<f32>,
}

/// Applies the wall-chain rule, looking from `facing_rad` (rad from body x), to the segments
/// extracted from `sweep`, which begins where the rules start looking (`rule_start_rad` from
/// `facing_rad`).
pub(super) fn choose_heading<const N: usize, const S: usize>(
    walls: &WallSegments<S>,
    sweep: &Sweep<N>,
    facing_rad: f32,
    cfg: &GuidanceConfig,
) -> HeadingChoice {
    let segments = walls.segments();
    // A segment is in the window when its first hit's beam is: the hit projected onto the
    // fitted line can land a hair clockwise of the window's start, and a wall cut there by the
    // sweep would then count as starting a full turn later and drop out of the chain.
    let in_window = |k: usize| sweep.rel_rad(segments[k].first_pos) < cfg.rule_sweep_rad;
    let Some(first) = (0..segments.len()).find(|&k| in_window(k)) else {
        return HeadingChoice {
            rule: HeadingRule::NoWall,
            body_rad: None,
        };
    };
    let mut last = first;
    let mut gap = None;
    while last + 1 < segments.len() && in_window(last + 1) {
        if walls.gaps()[last].width_m >= cfg.min_gap_width_m {
            gap = Some(last);
            break;
        }
        last += 1;
    }
    let direction = segments[last].direction_rad();
    let backwards = normalize_angle(direction - facing_rad).abs() > FRAC_PI_2;
    let rule = if gap.is_none() && backwards {
        HeadingRule::DeadEnd { segment: last }
    } else {
        HeadingRule::FollowWall { segment: last, gap }
    };
    HeadingChoice {
        rule,
        body_rad: Some(direction),
    }
}

/// Distances to the nearest hit on either side of an axis (the followed wall's direction, or
/// body x without one), among hits within 45° of the axis' normals, m; `None` for a side with
/// no hit. Measured about the axis, not the body, so a vehicle that does not turn to its
/// heading still sees a corridor's width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideClearance {
    pub left_m: Option<f32>,
    pub right_m: Option<f32>,
    /// The axis, a unit vector in the sensor frame; "left" is its counter-clockwise side.
    pub axis: Vec2,
}

impl SideClearance {
    pub(super) fn measure<const N: usize>(sweep: &Sweep<N>, axis_rad: Option<f32>) -> Self {
        let axis = axis_rad.map_or(Vec2::new(1.0, 0.0), |a| {
            Vec2::new(libm::cosf(a), libm::sinf(a))
        });
        let mut left = f32::INFINITY;
        let mut right = f32::INFINITY;
        for pos in (0..sweep.len()).filter(|&p| sweep.is_usable(p)) {
            let u = sweep.unit(pos);
            let (along, across) = (u.dot(axis), axis.cross(u));
            if along.abs() > across.abs() {
                continue;
            }
            let lateral = sweep.range_m(pos) * across.abs();
            if across > 0.0 {
                left = left.min(lateral);
            } else {
                right = right.min(lateral);
            }
        }
        Self {
            left_m: left.is_finite().then_some(left),
            right_m: right.is_finite().then_some(right),
            axis,
        }
    }

    /// Left plus right, when both sides have a hit.
    pub fn free_width_m(&self) -> Option<f32> {
        Some(self.left_m? + self.right_m?)
    }

    /// Seed 002, Fig. 5: under twice the wall-follow distance the vehicle keeps to the middle.
    pub fn is_narrow(&self, cfg: &GuidanceConfig) -> bool {
        self.free_width_m().is_some_and(|w| w < 2.0 * cfg.r_goal_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::{Beam, Scan};

    /// One-degree beams all round: a wall along y = -1 seen from -120° (the rules' start) to
    /// -60°, its hits alternately 1.5 cm beyond and short of it (range noise), open space, and
    /// a wall along y = +1 from 30° to 150°.
    fn right_wall_at_the_window_start() -> Scan<360> {
        let mut scan = Scan::new(0.0);
        for deg in -180..180 {
            let a = (deg as f32).to_radians();
            let beam = if (-120..=-60).contains(&deg) {
                let noise = if deg % 2 == 0 { 0.015 } else { -0.015 };
                Beam::new(a, -1.0 / libm::sinf(a) + noise)
            } else if (30..=150).contains(&deg) {
                Beam::new(a, 1.0 / libm::sinf(a))
            } else {
                Beam::invalid(a)
            };
            scan.push(beam).unwrap();
        }
        scan
    }

    #[test]
    fn a_wall_cut_at_the_window_start_is_in_the_window() {
        let cfg = GuidanceConfig::default();
        let sweep = Sweep::new(&right_wall_at_the_window_start(), cfg.rule_start_rad);
        let mut walls = WallSegments::<8>::default();
        walls.extract_sweep(&sweep, &cfg);
        let first = walls.segments()[0];
        // The case this is about: the first hit, projected onto the line, lies just clockwise
        // of where the rules start.
        let start = libm::atan2f(first.start_m.y, first.start_m.x);
        assert!(start < cfg.rule_start_rad, "{start}");
        assert_eq!(first.first_pos, 0);
        let choice = choose_heading(&walls, &sweep, 0.0, &cfg);
        // The chain starts at the right wall and stops at the opening after it.
        assert_eq!(
            choice.rule,
            HeadingRule::FollowWall {
                segment: 0,
                gap: Some(0)
            }
        );
        assert!(choice.body_rad.unwrap().abs() < 0.05, "{choice:?}");
    }
}
