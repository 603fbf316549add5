//! The openings between consecutive wall segments and how wide they are (seed 002, Fig. 5).

use super::prls::WallSegment;
use super::sweep::Sweep;
use crate::geom::Vec2;
use core::f32::consts::{PI, TAU};

/// The opening between segment `after` and segment `after + 1` (for the gap across the start
/// of a full-turn sweep, between the last segment and the first).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gap {
    /// Index of the segment before the gap; the one after is `after + 1`.
    pub after: usize,
    /// Last hit of the segment before and first hit of the one after, sensor frame, m.
    pub from_m: Vec2,
    pub to_m: Vec2,
    /// Free width across the gap, m: the shortest distance from either edge of the opening to
    /// any hit on its far side (within half a turn, not back along the edge's own wall), so
    /// clutter in a door (a person) narrows the door. Hits are discrete, so this exceeds the
    /// true opening by up to one beam spacing at each edge.
    pub width_m: f32,
    /// The two hits `width_m` apart, sensor frame, m, in sweep order ...
    pub narrowest_m: [Vec2; 2],
    /// ... and their sweep positions: a narrow gap is closed between them.
    pub narrowest_pos: [usize; 2],
}

impl Gap {
    /// True for sweep positions strictly between the narrowest pair (across the sweep's start
    /// for the seam gap).
    pub fn spans(&self, pos: usize) -> bool {
        let [lo, hi] = self.narrowest_pos;
        if lo < hi {
            lo < pos && pos < hi
        } else {
            pos > lo || pos < hi
        }
    }
}

/// Fills `gaps[k]` for the opening after `segments[k]`; returns the gap across the start of
/// the sweep, between the last segment and the first, when the sweep is an ordered full turn
/// (no hole wider than `max_step_rad` where it closes). In a full turn the far side of any
/// opening may lie past the sweep's start, so every search goes round.
pub(super) fn measure_gaps<const N: usize>(
    segments: &[WallSegment],
    gaps: &mut [Gap],
    sweep: &Sweep<N>,
    max_step_rad: f32,
) -> Option<Gap> {
    let full_turn = sweep.len() >= 2
        && sweep.is_ordered()
        && TAU - sweep.rel_rad(sweep.len() - 1) + sweep.rel_rad(0) <= max_step_rad;
    for (k, gap) in gaps.iter_mut().enumerate() {
        *gap = measure(k, &segments[k], &segments[k + 1], sweep, full_turn);
    }
    match (segments.first(), segments.last()) {
        (Some(first), Some(last)) if full_turn && segments.len() >= 2 => {
            Some(measure(segments.len() - 1, last, first, sweep, true))
        }
        _ => None,
    }
}

/// The gap from the end of `a` to the start of `b`; `wraps` lets the searches go round past the
/// end of the sweep (a full turn).
fn measure<const N: usize>(
    k: usize,
    a: &WallSegment,
    b: &WallSegment,
    sweep: &Sweep<N>,
    wraps: bool,
) -> Gap {
    let from = sweep.hit(a.last_pos).unwrap_or(a.end_m);
    let to = sweep.hit(b.first_pos).unwrap_or(b.start_m);
    let mut best = Narrowest {
        squared_m2: (to - from).norm_squared(),
        pts: [from, to],
        pos: [a.last_pos, b.first_pos],
    };
    // Counter-clockwise from the edge before the gap, clockwise from the edge after it.
    let after = Edge {
        pos: a.last_pos,
        at: from,
        along: a.end_m - a.start_m,
        forward: true,
    };
    let before = Edge {
        pos: b.first_pos,
        at: to,
        along: b.start_m - b.end_m,
        forward: false,
    };
    let (round_after, round_before) = if wraps {
        (0..a.first_pos, b.last_pos + 1..sweep.len())
    } else {
        (0..0, 0..0)
    };
    after.search(
        sweep,
        (a.last_pos + 1..sweep.len()).chain(round_after),
        &mut best,
    );
    before.search(
        sweep,
        (0..b.first_pos).rev().chain(round_before.rev()),
        &mut best,
    );
    Gap {
        after: k,
        from_m: from,
        to_m: to,
        width_m: libm::sqrtf(best.squared_m2),
        narrowest_m: best.pts,
        narrowest_pos: best.pos,
    }
}

/// The closest pair found so far (squared distance while searching: one root per gap).
struct Narrowest {
    squared_m2: f32,
    pts: [Vec2; 2],
    pos: [usize; 2],
}

/// One edge of an opening and the way across it.
struct Edge {
    pos: usize,
    at: Vec2,
    /// Along the edge's own wall, pointing out into the opening.
    along: Vec2,
    /// True when the far side lies at later sweep positions.
    forward: bool,
}

impl Edge {
    /// Looks for the hit nearest the edge across the opening: within half a turn of it on
    /// the far side, and not back along its own wall (the same wall seen again past the end
    /// of the sweep is not across the gap). In an ordered sweep the search stops once the
    /// beams turn so far from the edge that no hit on them can be nearer than the best.
    fn search<const N: usize>(
        &self,
        sweep: &Sweep<N>,
        positions: impl Iterator<Item = usize>,
        best: &mut Narrowest,
    ) {
        let (edge_unit, edge_range) = (sweep.unit(self.pos), sweep.range_m(self.pos));
        for pos in positions {
            let turn = if self.forward {
                sweep.rel_rad(pos) - sweep.rel_rad(self.pos)
            } else {
                sweep.rel_rad(self.pos) - sweep.rel_rad(pos)
            };
            let turn = if turn < 0.0 { turn + TAU } else { turn };
            if turn > PI {
                if sweep.is_ordered() {
                    break;
                }
                continue;
            }
            if sweep.is_ordered() && sweep.is_usable(self.pos) {
                // Nothing on a ray `turn` away from the edge's is nearer than this.
                let u = sweep.unit(pos);
                let bound = if u.dot(edge_unit) >= 0.0 {
                    edge_range * u.cross(edge_unit).abs()
                } else {
                    edge_range
                };
                if bound * bound >= best.squared_m2 {
                    break;
                }
            }
            let Some(q) = sweep.hit(pos) else { continue };
            let d = (q - self.at).norm_squared();
            if d < best.squared_m2 && (q - self.at).dot(self.along) >= 0.0 {
                let pair = if self.forward {
                    ([self.at, q], [self.pos, pos])
                } else {
                    ([q, self.at], [pos, self.pos])
                };
                *best = Narrowest {
                    squared_m2: d,
                    pts: pair.0,
                    pos: pair.1,
                };
            }
        }
    }
}
