//! The runner's collision check without a grid search at every check.
//!
//! Distance to the nearest wall (capped) is 1-Lipschitz in the position: after measuring `c` at
//! `p`, it is at least `c - |q - p|` anywhere `q`. The runner only needs the exact value when it
//! might set a new minimum clearance or mean a crash, i.e. when it could be below some floor;
//! while that bound stays above the floor (with a margin far beyond rounding) the search is
//! skipped, and the run's outputs are the same as with a search at every check.

use crate::world::scene::Scene;

/// Rounding allowance of the bound, m (the distances are computed to about 1e-15 m).
const MARGIN_M: f64 = 1e-9;

/// The last clearance measured and where.
#[derive(Clone, Debug, Default)]
pub struct ClearanceWatch {
    last: Option<([f64; 2], f64)>,
}

impl ClearanceWatch {
    /// The clearance at `p` (capped at `cap_m`, as [`Scene::clearance`]), or `None` when it is
    /// certainly at least `floor_m`.
    pub fn below(&mut self, scene: &Scene, p: [f64; 2], cap_m: f64, floor_m: f64) -> Option<f64> {
        if let Some((q, c)) = self.last {
            let moved = ((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1])).sqrt();
            if c - moved - MARGIN_M >= floor_m {
                return None;
            }
        }
        let c = scene.clearance(p, cap_m);
        self.last = Some((p, c));
        Some(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::World;

    #[test]
    fn skips_only_what_cannot_be_below_the_floor() {
        let world = World::shipped("office").unwrap().unwrap();
        let scene = Scene::new(&world);
        let mut watch = ClearanceWatch::default();
        let (mut skipped, mut min) = (0, f64::INFINITY);
        // A walk across the office in 5 mm steps, as the runner checks at 100 Hz.
        let (a, b) = (
            [world.start[0], world.start[1]],
            [world.start[0] + 6.0, world.start[1] + 2.0],
        );
        for k in 0..=2000 {
            let f = k as f64 / 2000.0;
            let p = [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f];
            let exact = scene.clearance(p, 2.0);
            match watch.below(&scene, p, 2.0, min.max(0.3)) {
                Some(c) => assert_eq!(c, exact),
                None => {
                    assert!(exact >= min.max(0.3), "skipped {exact} at {p:?}");
                    skipped += 1;
                }
            }
            min = min.min(exact);
        }
        assert!(
            skipped > 500,
            "the bound should spare most searches: {skipped}"
        );
    }
}
