//! Synthetic maps with known answers: rooms drawn as wall segments, scanned by an ideal lidar
//! that, like the XV-11, returns nothing when no wall lies within range.
#![allow(dead_code)] // each test binary uses a different part

pub mod survey;

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_explore::{ExploreConfig, Explorer};
use plumbline_slam::grid::PreparedScan;

pub type Wall = [f32; 4];

pub const MAX_RANGE_M: f32 = 6.0;

/// Distance along the ray from `o` in direction `d` (unit) to the wall, if it is hit.
fn ray_hits(o: Vec2, d: Vec2, w: &Wall) -> Option<f32> {
    let (a, b) = (Vec2::new(w[0], w[1]), Vec2::new(w[2], w[3]));
    let e = b - a;
    let denom = d.cross(e);
    if denom.abs() < 1e-9 {
        return None;
    }
    let t = (a - o).cross(e) / denom;
    let u = (a - o).cross(d) / denom;
    (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

/// A 720-beam scan of `walls` from `pose`, in the sensor frame.
pub fn scan(walls: &[Wall], pose: Pose2) -> PreparedScan {
    let mut out = PreparedScan::new();
    for b in 0..720 {
        let a = b as f32 * core::f32::consts::TAU / 720.0;
        let d = Vec2::new((pose.theta + a).cos(), (pose.theta + a).sin());
        let nearest = walls
            .iter()
            .filter_map(|w| ray_hits(pose.translation(), d, w))
            .fold(f32::INFINITY, f32::min);
        if nearest <= MAX_RANGE_M {
            out.push_hit(Vec2::new(a.cos(), a.sin()) * nearest);
        }
    }
    out
}

/// A rectangle's four walls, with the openings `(wall, from, to)` left out: `wall` 0 is the
/// bottom, 1 the right, 2 the top, 3 the left side; `from`/`to` are along that side's axis.
pub fn room(x0: f32, y0: f32, x1: f32, y1: f32, openings: &[(usize, f32, f32)]) -> Vec<Wall> {
    let sides = [
        (0, [x0, y0, x1, y0]),
        (1, [x1, y0, x1, y1]),
        (2, [x0, y1, x1, y1]),
        (3, [x0, y0, x0, y1]),
    ];
    let mut walls = Vec::new();
    for (side, w) in sides {
        let horizontal = side % 2 == 0;
        let (lo, hi) = if horizontal {
            (w[0], w[2])
        } else {
            (w[1], w[3])
        };
        let mut cuts: Vec<(f32, f32)> = openings
            .iter()
            .filter(|o| o.0 == side)
            .map(|o| (o.1, o.2))
            .collect();
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut start = lo;
        for (from, to) in cuts.into_iter().chain([(hi, hi)]) {
            if from > start {
                walls.push(if horizontal {
                    [start, w[1], from, w[1]]
                } else {
                    [w[0], start, w[0], from]
                });
            }
            start = to;
        }
    }
    walls
}

/// An explorer whose map holds scans of `walls` from each of `poses`, clock at 0.
pub fn explorer(walls: &[Wall], poses: &[Pose2]) -> Explorer {
    explorer_with(ExploreConfig::default(), walls, poses)
}

pub fn explorer_with(config: ExploreConfig, walls: &[Wall], poses: &[Pose2]) -> Explorer {
    let mut e = Explorer::new(config).unwrap();
    for &p in poses {
        e.map_mut().insert_at(p, &scan(walls, p)).unwrap();
    }
    e.set_time(0.0);
    e
}
