//! The grid's long operations split among threads give exactly what one pass gives: a rebuild
//! from many keyframes (inserted in halves and added up), also when a count saturates, and
//! seeing through with many scans (counted in shares and summed). A rebuild is the same
//! whatever order the keyframes come in.

use plumbline_core::geom::Pose2;
mod common;

use common::room_scan;
use plumbline_slam::grid::{GridConfig, OccupancyGrid, PreparedScan};

fn grid() -> OccupancyGrid {
    OccupancyGrid::new(GridConfig::default()).unwrap()
}

/// A grid in which every beam clears every cell it passes: inserting scans one by one then
/// gives the counts of a rebuild (with the default, a beam's misses depend on the hits already
/// there, which a rebuild takes all in before any miss).
fn grid_clearing_all() -> OccupancyGrid {
    OccupancyGrid::new(GridConfig {
        solid_hits: 0,
        ..GridConfig::default()
    })
    .unwrap()
}

fn rebuilt(scans: &[(Pose2, PreparedScan)], mut g: OccupancyGrid) -> OccupancyGrid {
    g.rebuild(scans.iter().map(|(pose, scan)| (*pose, scan)))
        .unwrap();
    g
}

/// Keyframes walking around a 6 m x 4 m room, 360 beams each.
fn keyframes(n: usize) -> Vec<(Pose2, PreparedScan)> {
    (0..n)
        .map(|k| {
            let a = k as f32 * 0.05;
            let pose = Pose2::new(3.0 + 2.0 * a.cos(), 2.0 + 1.2 * a.sin(), a * 1.7);
            let beams = room_scan(pose, 6.0, 4.0, 360);
            (pose, PreparedScan::from_beams(&beams, 10.0, None).unwrap())
        })
        .collect()
}

fn one_by_one(scans: &[(Pose2, PreparedScan)]) -> OccupancyGrid {
    let mut g = grid_clearing_all();
    for (pose, scan) in scans {
        g.insert(*pose, scan).unwrap();
    }
    g
}

fn assert_same(a: &OccupancyGrid, b: &OccupancyGrid) {
    assert_eq!(a.bounds(), b.bounds());
    assert_eq!(a.scans(), b.scans());
    let r = a.bounds().unwrap();
    let mut observed = 0;
    for j in r.min.j..=r.max.j {
        for i in r.min.i..=r.max.i {
            let c = plumbline_slam::grid::Cell::new(i, j);
            assert_eq!(a.counts(c), b.counts(c), "{c:?}");
            observed += usize::from(a.counts(c) != (0, 0));
        }
    }
    assert!(observed > 1000, "{observed} cells observed");
}

#[test]
fn a_rebuild_from_many_keyframes_is_the_one_by_one_grid() {
    let scans = keyframes(300);
    assert_same(&rebuilt(&scans, grid_clearing_all()), &one_by_one(&scans));
}

#[test]
fn a_rebuild_is_the_same_in_any_order() {
    // Few keyframes go in on one thread, many in halves; either way, and whichever keyframes
    // fall in which half, the counts are the same.
    for n in [100, 300] {
        let mut scans = keyframes(n);
        let forward = rebuilt(&scans, grid());
        let all_clear = rebuilt(&scans, grid_clearing_all());
        let r = forward.bounds().unwrap();
        let kept = (r.min.j..=r.max.j)
            .flat_map(|j| (r.min.i..=r.max.i).map(move |i| plumbline_slam::grid::Cell::new(i, j)))
            .filter(|&c| forward.counts(c).1 < all_clear.counts(c).1)
            .count();
        assert!(kept > 0, "some beams ran along the walls");
        scans.reverse();
        assert_same(&forward, &rebuilt(&scans, grid()));
        scans.rotate_left(n / 3);
        assert_same(&forward, &rebuilt(&scans, grid()));
    }
}

#[test]
fn a_rebuild_whose_counts_saturate_is_the_one_by_one_grid() {
    // Keyframes standing still: their cell gains 360 misses each, 72,360 in all, and its
    // counts saturate (are halved) on the way.
    let mut scans = keyframes(150);
    let still = scans[0].clone();
    scans.extend(std::iter::repeat_n(still, 200));
    let g = one_by_one(&scans);
    let origin = g.frame().cell_of(scans[0].0.translation());
    assert!(g.counts(origin).1 < 60_000, "{:?}", g.counts(origin));
    assert_same(&rebuilt(&scans, grid_clearing_all()), &g);
}

#[test]
fn seeing_through_with_many_scans_is_seeing_through_with_each() {
    // A few keyframes make a map with cells hit once or twice (the room's corners and the
    // cells where walls are seen at a grazing angle); many scans then see through it.
    let all = keyframes(400);
    let base = one_by_one(&all[..6]);
    let scans: Vec<(Pose2, &PreparedScan)> = all[6..].iter().map(|(p, s)| (*p, s)).collect();
    let mut together = base.clone();
    together.see_through(scans.iter().copied(), 2).unwrap();
    let mut each = base.clone();
    for &scan in &scans {
        each.see_through([scan], 2).unwrap();
    }
    assert_same(&together, &each);
    let r = base.bounds().unwrap();
    let changed = (r.min.j..=r.max.j)
        .flat_map(|j| (r.min.i..=r.max.i).map(move |i| plumbline_slam::grid::Cell::new(i, j)))
        .filter(|&c| together.counts(c) != base.counts(c))
        .count();
    assert!(changed > 0, "the scans saw through something");
}
