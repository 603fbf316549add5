//! Hits near the vehicle remembered in the world frame, so the guard still sees a wall the
//! lidar has stopped seeing: a thin wall's end approached edge-on returns nothing (beams
//! meeting it at a grazing angle are lost), though it was in plain view a moment before.
//!
//! How long: a hit is kept `obstacle_memory_s` after it was last seen, and longer (up to
//! `obstacle_hold_s`) while the vehicle stays within its stopping distance
//! (`max_speed / approach_rate`) of where it last saw it. A vehicle that lingers in a doorway
//! and then turns along the wall has not passed the jamb it can no longer see, and a clock
//! alone forgot it; the guard never lets the vehicle close more than that distance on a
//! remembered hit (from the guard's reach down to `r_min`), so approaching one cannot make
//! the vehicle forget it, while flying on past it does.
//!
//! Each place is stored once (hits within [`MERGE_M`] of a remembered one refresh it), so the
//! walls round a vehicle that hovers do not crowd out the jamb it saw a few revolutions ago;
//! when the memory is full, the hit seen longest ago gives way.

use super::sweep::Sweep;
use crate::geom::{Pose2, Vec2};

/// Places kept: a metre's reach round a vehicle in a doorway holds about 5 m of wall, 100
/// places [`MERGE_M`] apart.
pub const REMEMBERED_HITS: usize = 192;

/// Hits closer than this to a remembered one are the same place, m: the range noise of a
/// cheap lidar, well under the guard's margin.
pub const MERGE_M: f32 = 0.05;

/// Remembered places, world frame: where each hit was, when it was last seen and where the
/// vehicle was then.
#[derive(Clone, Debug)]
pub struct NearMemory {
    world_m: [Vec2; REMEMBERED_HITS],
    seen_from_m: [Vec2; REMEMBERED_HITS],
    seen_s: [f64; REMEMBERED_HITS],
    len: usize,
}

impl Default for NearMemory {
    fn default() -> Self {
        Self {
            world_m: [Vec2::ZERO; REMEMBERED_HITS],
            seen_from_m: [Vec2::ZERO; REMEMBERED_HITS],
            seen_s: [0.0; REMEMBERED_HITS],
            len: 0,
        }
    }
}

/// How long remembered hits count (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Recall {
    /// Every hit counts this long after it was last seen, s.
    pub memory_s: f32,
    /// A hit counts this long while the vehicle is within `hold_m` of where it last saw it, s.
    pub hold_s: f32,
    pub hold_m: f32,
}

impl NearMemory {
    /// Stores the hits of `sweep` nearer than `within_m`, seen from `pose` at `stamp_s`.
    /// A clock that runs backwards (a new flight, a replayed log) starts the memory afresh.
    pub fn remember<const N: usize>(
        &mut self,
        sweep: &Sweep<N>,
        pose: Pose2,
        stamp_s: f64,
        within_m: f32,
    ) {
        let newest = self.seen_s[..self.len]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        if !stamp_s.is_finite() || stamp_s < newest {
            self.len = 0;
        }
        if !stamp_s.is_finite() {
            return;
        }
        let from = pose.translation();
        for pos in (0..sweep.len()).filter(|&p| sweep.is_usable(p) && sweep.range_m(p) < within_m) {
            let p = pose.transform(sweep.point(pos));
            let known = self.world_m[..self.len]
                .iter()
                .position(|&q| (q - p).norm_squared() < MERGE_M * MERGE_M);
            let slot = match known {
                Some(k) => k,
                None if self.len < REMEMBERED_HITS => {
                    self.len += 1;
                    self.world_m[self.len - 1] = p;
                    self.len - 1
                }
                None => {
                    let stalest = (0..self.len)
                        .min_by(|&a, &b| self.seen_s[a].total_cmp(&self.seen_s[b]))
                        .unwrap_or(0);
                    self.world_m[stalest] = p;
                    stalest
                }
            };
            self.seen_s[slot] = stamp_s;
            self.seen_from_m[slot] = from;
        }
    }

    /// Remembered hits last seen before `now_s` that still count (see [`Recall`]), as (unit
    /// direction, range) in the body frame of `pose`, worked out once: the guard and the
    /// evasion go over them many times a step.
    pub fn recalled(&self, pose: Pose2, now_s: f64, recall: Recall) -> Recalled {
        let to_body = pose.inverse();
        let here = pose.translation();
        let mut out = Recalled {
            hits: [(Vec2::ZERO, 0.0); REMEMBERED_HITS],
            len: 0,
        };
        for i in 0..self.len {
            let age = now_s - self.seen_s[i];
            let counts = age > 0.0
                && (age <= f64::from(recall.memory_s)
                    || (age <= f64::from(recall.hold_s)
                        && (here - self.seen_from_m[i]).norm() <= recall.hold_m));
            if !counts {
                continue;
            }
            let p = to_body.transform(self.world_m[i]);
            let r = p.norm();
            if r > 0.0 {
                out.hits[out.len] = (p * (1.0 / r), r);
                out.len += 1;
            }
        }
        out
    }
}

/// The remembered hits that count this step, body frame: (unit direction, range).
pub struct Recalled {
    hits: [(Vec2, f32); REMEMBERED_HITS],
    len: usize,
}

impl Recalled {
    pub fn iter(&self) -> impl Iterator<Item = (Vec2, f32)> + '_ {
        self.hits[..self.len].iter().copied()
    }
}
