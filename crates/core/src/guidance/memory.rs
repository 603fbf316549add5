//! Hits near the vehicle remembered for a moment in the world frame, so the guard still sees a
//! wall the lidar has stopped seeing: a thin wall's end approached edge-on returns nothing
//! (beams meeting it at a grazing angle are lost), though it was in plain view a second before.

use super::sweep::Sweep;
use crate::geom::{Pose2, Vec2};

/// Points kept (older ones are overwritten first): about two revolutions of the hits within
/// a metre of the vehicle in a doorway.
pub const REMEMBERED_HITS: usize = 256;

/// A ring of recent near hits, world frame, with the time each was seen.
#[derive(Clone, Debug)]
pub struct NearMemory {
    world_m: [Vec2; REMEMBERED_HITS],
    seen_s: [f64; REMEMBERED_HITS],
    len: usize,
    next: usize,
}

impl Default for NearMemory {
    fn default() -> Self {
        Self {
            world_m: [Vec2::ZERO; REMEMBERED_HITS],
            seen_s: [0.0; REMEMBERED_HITS],
            len: 0,
            next: 0,
        }
    }
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
            self.next = 0;
        }
        if !stamp_s.is_finite() {
            return;
        }
        for pos in (0..sweep.len()).filter(|&p| sweep.is_usable(p) && sweep.range_m(p) < within_m) {
            self.world_m[self.next] = pose.transform(sweep.point(pos));
            self.seen_s[self.next] = stamp_s;
            self.next = (self.next + 1) % REMEMBERED_HITS;
            self.len = (self.len + 1).min(REMEMBERED_HITS);
        }
    }

    /// Remembered hits seen before `now_s` and no more than `max_age_s` earlier, as (unit
    /// direction, range) in the body frame of `pose`.
    pub fn recalled(
        &self,
        pose: Pose2,
        now_s: f64,
        max_age_s: f32,
    ) -> impl Iterator<Item = (Vec2, f32)> + '_ {
        let to_body = pose.inverse();
        (0..self.len)
            .filter(move |&i| {
                let age = now_s - self.seen_s[i];
                age > 0.0 && age <= f64::from(max_age_s)
            })
            .filter_map(move |i| {
                let p = to_body.transform(self.world_m[i]);
                let r = p.norm();
                (r > 0.0).then(|| (p * (1.0 / r), r))
            })
    }
}
