//! Rebuilding the whole map from its keyframes, as after a loop closure: 1,500 keyframes (about
//! what the Intel lab log gives at one keyframe every 0.5 m or 0.5 rad) of 180 and 360 beams,
//! in a 30 m square building whose 4 m wide ring corridor the keyframes follow, so beams run
//! from 2 m across the corridor to 26 m along it (the mean is printed). Also one scan inserted
//! on its own, the online cost per keyframe, and the map images made from the rebuilt grid.

use criterion::{criterion_group, criterion_main, Criterion};
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_slam::grid::{GridConfig, OccupancyGrid, PreparedScan, Raster};
use plumbline_slam::map_files;
use std::hint::black_box;

const KEYFRAMES: usize = 1500;
const MAX_RANGE_M: f32 = 30.0;

/// The building: an outer and an inner square wall, with a few room dividers inside.
fn walls() -> Vec<[Vec2; 2]> {
    let sq = |a: f32, b: f32| {
        let c = [
            Vec2::new(a, a),
            Vec2::new(b, a),
            Vec2::new(b, b),
            Vec2::new(a, b),
        ];
        (0..4).map(move |k| [c[k], c[(k + 1) % 4]])
    };
    let mut w: Vec<_> = sq(0.0, 30.0).chain(sq(4.0, 26.0)).collect();
    for x in [10.0, 15.0, 20.0] {
        w.push([Vec2::new(x, 4.0), Vec2::new(x, 12.0)]);
    }
    w
}

/// Distance along `d` (unit) from `o` to the nearest wall.
fn cast(o: Vec2, d: Vec2, walls: &[[Vec2; 2]]) -> Option<f32> {
    walls
        .iter()
        .filter_map(|[a, b]| {
            let e = *b - *a;
            let den = d.cross(e);
            if den.abs() < 1e-9 {
                return None;
            }
            let t = (*a - o).cross(e) / den;
            let u = (*a - o).cross(d) / den;
            (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
        })
        .fold(None, |m: Option<f32>, t| Some(m.map_or(t, |m| m.min(t))))
}

/// Keyframe poses around the ring corridor, heading along it.
fn poses() -> Vec<Pose2> {
    let corners: [(f32, f32); 4] = [(2.0, 2.0), (28.0, 2.0), (28.0, 28.0), (2.0, 28.0)];
    (0..KEYFRAMES)
        .map(|k| {
            let s = k as f32 / KEYFRAMES as f32 * 4.0;
            let (side, u) = (s as usize, s.fract());
            let (a, b) = (corners[side], corners[(side + 1) % 4]);
            let heading = (b.1 - a.1).atan2(b.0 - a.0);
            Pose2::new(
                a.0 + u * (b.0 - a.0),
                a.1 + u * (b.1 - a.1),
                heading + 0.3 * (k as f32).sin(),
            )
        })
        .collect()
}

fn keyframes(beams: usize) -> (Vec<Pose2>, Vec<PreparedScan>, f32) {
    let w = walls();
    let poses = poses();
    let mut total_range = 0.0;
    let scans = poses
        .iter()
        .map(|p| {
            let mut s = PreparedScan::new();
            for k in 0..beams {
                let a = k as f32 * core::f32::consts::TAU / beams as f32;
                let d = Vec2::new(a.cos(), a.sin());
                let r = cast(p.translation(), p.rotate(d), &w).unwrap_or(MAX_RANGE_M);
                total_range += r.min(MAX_RANGE_M);
                if r <= MAX_RANGE_M {
                    s.push_hit(d * r);
                } else {
                    s.push_clear(d * MAX_RANGE_M);
                }
            }
            s
        })
        .collect();
    let mean = total_range / (KEYFRAMES * beams) as f32;
    (poses, scans, mean)
}

fn bench(c: &mut Criterion) {
    for beams in [180, 360] {
        let (poses, scans, mean_range) = keyframes(beams);
        let mut grid = OccupancyGrid::new(GridConfig::default()).unwrap();
        grid.rebuild(poses.iter().copied().zip(&scans)).unwrap();
        let b = grid.bounds().unwrap();
        eprintln!(
            "{beams} beams: mean range {mean_range:.2} m ({:.0} cells a beam), map {} x {} cells, \
             {} cells allocated, {:.1} MB, {} occupied",
            mean_range / 0.05,
            b.width(),
            b.height(),
            grid.allocated_cells(),
            grid.memory_bytes() as f64 / 1e6,
            grid.occupied_cells().count()
        );
        c.bench_function(
            &format!("rebuild {KEYFRAMES} keyframes x {beams} beams"),
            |bch| {
                bch.iter(|| {
                    grid.rebuild(poses.iter().copied().zip(&scans)).unwrap();
                    black_box(grid.scans())
                })
            },
        );
        c.bench_function(
            &format!("map images ({beams} beams): raster, PGM, PNG"),
            |bch| {
                bch.iter(|| {
                    let raster = Raster::from_grid(&grid).unwrap().unwrap();
                    let pgm = map_files::pgm_bytes(&raster);
                    let png = map_files::png_rgb(&raster, &poses).unwrap();
                    black_box((pgm.len(), png.len()))
                })
            },
        );
        c.bench_function(&format!("insert one {beams}-beam scan"), |bch| {
            let mut k = 0;
            bch.iter(|| {
                k = (k + 1) % KEYFRAMES;
                grid.insert(poses[k], &scans[k]).unwrap();
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
