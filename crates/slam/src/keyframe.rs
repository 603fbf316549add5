//! Keyframes: the scans the map is made of, kept compactly so an hour of flight fits.

use plumbline_core::geom::Pose2;
use plumbline_core::scan::{Beam, Scan};

/// One keyframe: its scan, where the tracker put it, and which submap it belongs to.
#[derive(Clone, Debug)]
pub struct Keyframe {
    pub stamp_s: f64,
    /// Only the valid beams: a keyframe is matched and drawn, never decoded again, and the
    /// invalid ones would be a third of the memory on a 180° lidar indoors.
    pub beams: Vec<Beam>,
    /// Pose in the tracker's frame (drifts; the graph's pose is the corrected one).
    pub tracking_pose: Pose2,
    pub submap: usize,
    /// Distance travelled from the first keyframe to this one along the tracked path, m.
    pub path_m: f32,
    /// The keyframe came from a failed match, or from a wide search whose pose the local map
    /// contradicted: its pose is a guess, and so is its edge in the graph (a weak one, which a
    /// loop closure can bend).
    pub predicted: bool,
}

impl Keyframe {
    /// Whether the keyframe still has its scan: one that only repeats what an older keyframe
    /// at nearly the same pose saw keeps its place in the graph but drops its beams
    /// ([`crate::backend`]), so flying the same rooms for an hour does not grow memory.
    pub fn has_scan(&self) -> bool {
        !self.beams.is_empty()
    }

    /// Drops the scan, keeping the pose-graph node.
    pub fn drop_scan(&mut self) {
        self.beams = Vec::new();
    }
}

impl Keyframe {
    pub fn new<const N: usize>(
        scan: &Scan<N>,
        tracking_pose: Pose2,
        submap: usize,
        path_m: f32,
        predicted: bool,
    ) -> Self {
        Self {
            stamp_s: scan.stamp_s,
            beams: scan.beams().iter().copied().filter(|b| b.valid).collect(),
            tracking_pose,
            submap,
            path_m,
            predicted,
        }
    }

    /// The keyframe as a scan again, for the matcher.
    pub fn to_scan<const N: usize>(&self, scan: &mut Scan<N>) {
        scan.clear(self.stamp_s);
        for &b in self.beams.iter().take(N) {
            // Cannot fail: at most N beams are pushed into an empty scan of N.
            let _ = scan.push(b);
        }
    }

    /// Hit points in the keyframe's own frame.
    pub fn points(&self) -> impl Iterator<Item = plumbline_core::geom::Vec2> + '_ {
        self.beams.iter().map(Beam::point)
    }
}
