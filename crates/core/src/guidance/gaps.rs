//! The openings between consecutive wall segments and how wide they are (seed 002, Fig. 5).

use super::prls::WallSegment;
use crate::geom::Vec2;

/// The opening between segment `after` and segment `after + 1`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gap {
    /// Index of the segment before the gap; the one after is `after + 1`.
    pub after: usize,
    /// Last hit of the segment before and first hit of the one after, sensor frame, m.
    pub from_m: Vec2,
    pub to_m: Vec2,
    /// Free width across the gap, m: the shortest distance from either edge of the opening to
    /// any hit on its far side, so clutter in a door (a person) narrows the door. Hits are
    /// discrete, so this exceeds the true opening by up to one beam spacing at each edge.
    pub width_m: f32,
    /// The two hits `width_m` apart, sensor frame, m, in sweep order ...
    pub narrowest_m: [Vec2; 2],
    /// ... and their sweep positions: a narrow gap is closed between them.
    pub narrowest_pos: [usize; 2],
}

/// Fills `gaps[k]` for the opening after `segments[k]`; `hit(pos)` is the usable hit at sweep
/// position `pos < sweep_len`, if any.
pub(super) fn measure_gaps(
    segments: &[WallSegment],
    gaps: &mut [Gap],
    sweep_len: usize,
    hit: impl Fn(usize) -> Option<Vec2>,
) {
    for (k, gap) in gaps.iter_mut().enumerate() {
        let (a, b) = (&segments[k], &segments[k + 1]);
        let from = hit(a.last_pos).unwrap_or(a.end_m);
        let to = hit(b.first_pos).unwrap_or(b.start_m);
        let mut best = ((to - from).norm(), [from, to], [a.last_pos, b.first_pos]);
        let mut consider = |d: f32, pts: [Vec2; 2], pos: [usize; 2]| {
            if d < best.0 {
                best = (d, pts, pos);
            }
        };
        // Only hits ahead of an edge along its own wall can close the opening: the same wall
        // seen again past the end of the sweep (behind the vehicle) is not across the gap.
        let (ahead, behind) = (a.end_m - a.start_m, b.end_m - b.start_m);
        for pos in a.last_pos + 1..sweep_len {
            if let Some(q) = hit(pos).filter(|&q| (q - from).dot(ahead) >= 0.0) {
                consider((q - from).norm(), [from, q], [a.last_pos, pos]);
            }
        }
        for pos in 0..b.first_pos {
            if let Some(p) = hit(pos).filter(|&p| (to - p).dot(behind) >= 0.0) {
                consider((to - p).norm(), [p, to], [pos, b.first_pos]);
            }
        }
        *gap = Gap {
            after: k,
            from_m: from,
            to_m: to,
            width_m: best.0,
            narrowest_m: best.1,
            narrowest_pos: best.2,
        };
    }
}
