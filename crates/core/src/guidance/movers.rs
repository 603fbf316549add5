//! Obstacles that walk toward the vehicle, found from the lidar alone: each revolution's hits
//! are laid over the previous revolution's in the world frame, and a surface that stands nearer
//! along the line of sight than the previous surface there did is closing in at that distance
//! over the revolution's time. A wall stays where it was (its hits match the previous ones to
//! within the range noise and the beam spacing), so only walking people and other movers give
//! a closing speed; a surface the vehicle had not seen before (round a corner, through a door)
//! matches nothing within a walker's reach and gives none.
//!
//! The field and the guard treat every hit as fixed, which is right for walls: a person walking
//! at the vehicle faster than it can fly away would still reach it. [`Movers::closing`] names
//! the most urgent mover, where it is, how wide it looks and how it moves (its seen hits'
//! centre tracked from revolution to revolution), so the step can get out of its way
//! ([`super::evade`]).

use super::config::GuidanceConfig;
use super::sweep::Sweep;
use crate::geom::{Pose2, Vec2};
use core::f32::consts::{PI, TAU};
use libm::{atan2f, ceilf};

/// World-bearing bins of the previous revolution's nearest hits (1° each).
pub const BEARING_BINS: usize = 360;
/// Neighbouring beams (each side) whose closing speeds are averaged: range noise on one beam
/// is centimetres, a person is a dozen beams wide at 2 m.
const SMOOTH_BEAMS: usize = 2;
/// Fewest matched beams in that window for a closing speed to count.
const SMOOTH_MIN_MATCHED: usize = 3;
/// Longest time between revolutions still compared, s: after a gap the previous surface says
/// nothing about the speed of the present one.
const MAX_GAP_S: f32 = 1.0;
/// Hits this close to the most urgent one, and closing at least half as fast as a mover must,
/// belong to the same mover, m: a person is half a metre across.
const CLUSTER_M: f32 = 0.6;
/// Weight of the newest revolution in the mover's smoothed velocity.
const VELOCITY_SMOOTHING: f32 = 0.5;
/// The seen hits of a round body lie in front of its centre by about this share of its half
/// width (the mean of cos over the visible half, π/4).
const CENTRE_BEHIND_HITS: f32 = 0.785;

/// A surface closing in on the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mover {
    /// Unit direction to its nearest hit, sensor frame.
    pub unit: Vec2,
    /// Range of that hit, m.
    pub range_m: f32,
    /// Speed at which its surface closes in on the vehicle, m/s (positive): its own motion,
    /// whatever the vehicle does.
    pub closing_m_s: f32,
    /// Estimated centre, sensor frame, m.
    pub centre_m: Vec2,
    /// Half its seen width across the line of sight, m.
    pub half_width_m: f32,
    /// Estimated velocity, sensor frame, m/s.
    pub velocity_m_s: Vec2,
}

/// The previous revolution's nearest hit per world bearing, and the mover being tracked.
#[derive(Clone, Debug)]
pub struct Movers {
    nearest_m: [Vec2; BEARING_BINS],
    filled: [bool; BEARING_BINS],
    origin: Vec2,
    stamp_s: Option<f64>,
    /// The tracked mover's centre and velocity, world frame.
    track: Option<(Vec2, Vec2)>,
    /// The side of its line of sight the vehicle is passing it on (see [`super::evade`]).
    side: Option<f32>,
}

impl Default for Movers {
    fn default() -> Self {
        Self {
            nearest_m: [Vec2::ZERO; BEARING_BINS],
            filled: [false; BEARING_BINS],
            origin: Vec2::ZERO,
            stamp_s: None,
            track: None,
            side: None,
        }
    }
}

fn bin_of(d: Vec2) -> usize {
    let a = atan2f(d.y, d.x) + PI;
    ((a / TAU * BEARING_BINS as f32) as usize).min(BEARING_BINS - 1)
}

impl Movers {
    /// The mover with the least time to reach `r_min` among those closing faster than
    /// `mover_min_closing_m_s` within the evasion horizon, then remembers this revolution.
    /// `sweep` is seen from `pose` at `stamp_s`.
    pub fn closing<const N: usize>(
        &mut self,
        sweep: &Sweep<N>,
        pose: Pose2,
        stamp_s: f64,
        cfg: &GuidanceConfig,
    ) -> Option<Mover> {
        let dt = self
            .stamp_s
            .map(|t| (stamp_s - t) as f32)
            .filter(|dt| *dt > 0.0 && *dt <= MAX_GAP_S);
        let found = dt.and_then(|dt| self.most_urgent(sweep, pose, dt, cfg).map(|m| (m, dt)));
        let mover = match found {
            Some((seen, dt)) => self.tracked(seen, pose, dt, cfg),
            None => {
                self.track = None;
                None
            }
        };
        if mover.is_none() {
            self.side = None;
        }
        self.remember(sweep, pose, stamp_s);
        mover
    }

    /// `seen` with its velocity from the track of its centre, once it was seen closing in on
    /// the revolution before as well, near where it is now: a single revolution's closing
    /// speed can be a wall's range noise or an estimate jump, two in a row at one place are
    /// a mover. A surface already too close to wait a revolution for (see [`too_close_to_wait`])
    /// counts at once, moving along its line of sight: a needless step aside costs a detour,
    /// a late one a contact. The track moves on either way.
    fn tracked(
        &mut self,
        seen: Mover,
        pose: Pose2,
        dt: f32,
        cfg: &GuidanceConfig,
    ) -> Option<Mover> {
        let centre = pose.transform(seen.centre_m);
        let along_sight = pose.rotate(seen.unit * -seen.closing_m_s);
        let confirmed = self
            .track
            .filter(|(last, _)| (centre - *last).norm() <= cfg.mover_max_speed_m_s * dt);
        let velocity = confirmed.map_or(along_sight, |(last, v)| {
            let raw = (centre - last) * (1.0 / dt);
            v + (raw - v) * VELOCITY_SMOOTHING
        });
        self.track = Some((centre, velocity));
        (confirmed.is_some() || too_close_to_wait(&seen, dt, cfg)).then(|| Mover {
            velocity_m_s: pose.inverse().rotate(velocity),
            ..seen
        })
    }

    /// The side the tracked mover is being passed on, if one was taken.
    pub fn side(&self) -> Option<f32> {
        self.side
    }

    /// Remembers the side the tracked mover is passed on.
    pub fn pass_on(&mut self, side: f32) {
        self.side = Some(side);
    }

    /// Closing speed of each beam's hit (NaN where nothing matched), then the urgent mover.
    fn most_urgent<const N: usize>(
        &self,
        sweep: &Sweep<N>,
        pose: Pose2,
        dt: f32,
        cfg: &GuidanceConfig,
    ) -> Option<Mover> {
        let gate_m = cfg.mover_max_speed_m_s * dt;
        let mut closing = [f32::NAN; N];
        for (pos, c) in closing.iter_mut().enumerate().take(sweep.len()) {
            if let Some(speed) = self.normal_speed(sweep, pos, pose, gate_m, cfg) {
                *c = speed / dt;
            }
        }
        let mut best: Option<(f32, usize, f32)> = None;
        for pos in 0..sweep.len() {
            if !sweep.is_usable(pos) {
                continue;
            }
            let Some(w) = smoothed(&closing[..sweep.len()], pos) else {
                continue;
            };
            let r = sweep.range_m(pos);
            if w < cfg.mover_min_closing_m_s {
                continue;
            }
            let time_s = (r - cfg.r_min_m()).max(0.0) / w;
            if time_s > cfg.evade_horizon_s || best.is_some_and(|(t, _, _)| t <= time_s) {
                continue;
            }
            best = Some((time_s, pos, w));
        }
        let (_, pos, w) = best?;
        Some(cluster(sweep, &closing[..sweep.len()], pos, w, cfg))
    }

    /// How far the surface at beam `pos` moved toward the vehicle since the previous
    /// revolution, m: the offset from the nearest previous hit along the surface's normal,
    /// which is the local line through the beam's neighbours. Along a fixed wall the nearest
    /// previous hit lies on the same line whatever the beam spacing, so the offset is the range
    /// noise only; a hit with no close neighbour (an edge, clutter) has no normal and gives
    /// nothing.
    fn normal_speed<const N: usize>(
        &self,
        sweep: &Sweep<N>,
        pos: usize,
        pose: Pose2,
        gate_m: f32,
        cfg: &GuidanceConfig,
    ) -> Option<f32> {
        let hit = sweep.hit(pos)?;
        let before = sweep.hit(pos.checked_sub(1)?)?;
        if pos + 1 >= sweep.len() {
            return None;
        }
        let after = sweep.hit(pos + 1)?;
        let spacing = cfg.max_point_spacing_m;
        if (before - hit).norm() > spacing || (after - hit).norm() > spacing {
            return None;
        }
        let tangent = pose.rotate(after - before);
        let length = tangent.norm();
        if length <= 0.0 {
            return None;
        }
        let p = pose.transform(hit);
        let mut normal = tangent.perp() * (1.0 / length);
        if normal.dot(pose.translation() - p) < 0.0 {
            normal = normal * -1.0;
        }
        let q = self.previous_near(p, gate_m)?;
        Some((p - q).dot(normal))
    }

    /// The previous revolution's hit nearest to `p` (world frame) within `gate_m`.
    fn previous_near(&self, p: Vec2, gate_m: f32) -> Option<Vec2> {
        let d = p - self.origin;
        let r = d.norm();
        // Bins a point within the gate can lie in, seen from where the previous scan was taken.
        let half = if r <= gate_m {
            BEARING_BINS / 2
        } else {
            let spread = libm::asinf((gate_m / r).min(1.0));
            (ceilf(spread / TAU * BEARING_BINS as f32) as usize + 1).min(BEARING_BINS / 2)
        };
        let centre = bin_of(d);
        let mut best: Option<(f32, Vec2)> = None;
        for k in 0..=2 * half {
            let bin = (centre + BEARING_BINS + k - half) % BEARING_BINS;
            if !self.filled[bin] {
                continue;
            }
            let q = self.nearest_m[bin];
            let e = (q - p).norm_squared();
            if e <= gate_m * gate_m && best.is_none_or(|(b, _)| e < b) {
                best = Some((e, q));
            }
        }
        best.map(|(_, q)| q)
    }

    fn remember<const N: usize>(&mut self, sweep: &Sweep<N>, pose: Pose2, stamp_s: f64) {
        self.filled = [false; BEARING_BINS];
        self.origin = pose.translation();
        self.stamp_s = stamp_s.is_finite().then_some(stamp_s);
        let mut range = [f32::INFINITY; BEARING_BINS];
        for pos in 0..sweep.len() {
            let Some(hit) = sweep.hit(pos) else {
                continue;
            };
            let p = pose.transform(hit);
            let bin = bin_of(p - self.origin);
            let r = sweep.range_m(pos);
            if r < range[bin] {
                range[bin] = r;
                self.nearest_m[bin] = p;
                self.filled[bin] = true;
            }
        }
    }
}

/// True when `seen` reaches `r_min` before the vehicle, starting once the next revolution
/// (`dt` from now) has confirmed it, could step its half width plus `r_min` aside at the speed
/// limit.
fn too_close_to_wait(seen: &Mover, dt: f32, cfg: &GuidanceConfig) -> bool {
    let reach_s = (seen.range_m - cfg.r_min_m()).max(0.0) / seen.closing_m_s;
    let aside_s = (cfg.r_min_m() + seen.half_width_m) / cfg.max_speed_m_s;
    reach_s < dt + aside_s
}

/// Mean closing speed over the beams around `pos`, when enough of them matched.
fn smoothed(closing: &[f32], pos: usize) -> Option<f32> {
    let lo = pos.saturating_sub(SMOOTH_BEAMS);
    let hi = (pos + SMOOTH_BEAMS + 1).min(closing.len());
    let (sum, n) = closing[lo..hi]
        .iter()
        .filter(|c| c.is_finite())
        .fold((0.0, 0), |(s, n), c| (s + c, n + 1));
    (n >= SMOOTH_MIN_MATCHED).then(|| sum / n as f32)
}

/// The mover whose most urgent hit is beam `pos` (closing at `w`): the hits near it that close
/// in too, their centre pushed back by the part of a round body the lidar cannot see.
fn cluster<const N: usize>(
    sweep: &Sweep<N>,
    closing: &[f32],
    pos: usize,
    w: f32,
    cfg: &GuidanceConfig,
) -> Mover {
    let near = sweep.point(pos);
    let unit = sweep.unit(pos);
    let (mut sum, mut n) = (Vec2::ZERO, 0.0f32);
    let (mut lo, mut hi) = (0.0f32, 0.0f32);
    for k in 0..sweep.len() {
        let Some(hit) = sweep.hit(k) else {
            continue;
        };
        let moving = smoothed(closing, k).is_some_and(|c| c >= 0.5 * cfg.mover_min_closing_m_s);
        if (hit - near).norm() > CLUSTER_M || !(moving || k == pos) {
            continue;
        }
        sum = sum + hit;
        n += 1.0;
        let across = unit.cross(hit - near);
        lo = lo.min(across);
        hi = hi.max(across);
    }
    let seen = sum * (1.0 / n);
    let half_width_m = 0.5 * (hi - lo);
    let centre_m = seen + unit * (CENTRE_BEHIND_HITS * half_width_m);
    Mover {
        unit,
        range_m: sweep.range_m(pos),
        closing_m_s: w,
        centre_m,
        half_width_m,
        velocity_m_s: unit * -w,
    }
}
