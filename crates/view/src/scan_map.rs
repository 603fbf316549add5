//! The map the view draws when the vehicle has none of its own: every revolution's beams laid
//! at the estimated pose, hits occupied and the cells a beam crossed free. It is what the
//! onboard estimate saw, so a drifting estimate shows as doubled walls.

use crate::snapshot::{OccupancyImage, FREE, OCCUPIED, UNKNOWN};
use plumbline_core::scan::Beam;
use std::sync::Arc;

/// Finest cell side, m.
const FINEST_M: f64 = 0.05;
/// Most cells along a side; a larger area gets coarser cells, so a map stays a few hundred
/// kilobytes of memory and a quick PNG.
const MAX_SIDE_CELLS: usize = 1000;

/// Where a beam ends in the map's frame, for a pose (x, y, yaw).
pub fn beam_end(pose: [f64; 3], beam: &Beam) -> [f64; 2] {
    let a = pose[2] + f64::from(beam.angle_rad);
    let r = f64::from(beam.range_m);
    [pose[0] + r * a.cos(), pose[1] + r * a.sin()]
}

/// The valid beams' ends for a pose, as the view's scan points.
pub fn scan_points(pose: [f64; 3], beams: &[Beam], out: &mut Vec<[f32; 2]>) {
    out.clear();
    out.extend(
        beams
            .iter()
            .filter(|b| b.valid)
            .map(|b| beam_end(pose, b).map(|v| v as f32)),
    );
}

/// An occupancy image built from scans.
pub struct ScanMap {
    image: OccupancyImage,
    /// The image as last handed out; a new copy is made only after the cells changed.
    shared: Option<Arc<OccupancyImage>>,
}

impl ScanMap {
    /// A map covering the square of half side `half_side_m` around `center` (m).
    pub fn new(center: [f64; 2], half_side_m: f64) -> Self {
        let half = if half_side_m.is_finite() {
            half_side_m.clamp(1.0, 1e4)
        } else {
            1.0
        };
        let resolution_m = (2.0 * half / MAX_SIDE_CELLS as f64).max(FINEST_M);
        let side = ((2.0 * half / resolution_m).ceil() as usize).clamp(1, MAX_SIDE_CELLS);
        Self {
            image: OccupancyImage {
                version: 0,
                origin_m: [center[0] - half, center[1] - half],
                resolution_m,
                width: side,
                height: side,
                cells: vec![UNKNOWN; side * side],
            },
            shared: None,
        }
    }

    fn cell(&self, p: [f64; 2]) -> Option<usize> {
        let m = &self.image;
        let cx = ((p[0] - m.origin_m[0]) / m.resolution_m).floor();
        let cy = ((p[1] - m.origin_m[1]) / m.resolution_m).floor();
        let inside = cx >= 0.0 && cy >= 0.0 && cx < m.width as f64 && cy < m.height as f64;
        inside.then(|| cy as usize * m.width + cx as usize)
    }

    /// Lays one revolution at `pose` (x, y, yaw in the map's frame); a non-finite pose is
    /// skipped. Cells outside the map are left out.
    pub fn add(&mut self, pose: [f64; 3], beams: &[Beam]) {
        if !pose.iter().all(|v| v.is_finite()) {
            return;
        }
        let m = &self.image;
        let step = m.resolution_m;
        // No beam crosses more of the map than its diagonal: longer ones are walked that far.
        let longest = step * (m.width + m.height) as f64;
        // The pose in cell units, so the walk below is one multiply-add per cell.
        let ox = (pose[0] - m.origin_m[0]) / step;
        let oy = (pose[1] - m.origin_m[1]) / step;
        let (w, h) = (m.width as f64, m.height as f64);
        let mut changed = false;
        for beam in beams.iter().filter(|b| b.valid && b.range_m.is_finite()) {
            let end = beam_end(pose, beam);
            let a = pose[2] + f64::from(beam.angle_rad);
            let (dx, dy) = (a.cos(), a.sin());
            let n = (f64::from(beam.range_m).min(longest) / step) as usize;
            for k in 0..n {
                let (cx, cy) = (ox + k as f64 * dx, oy + k as f64 * dy);
                if cx >= 0.0 && cy >= 0.0 && cx < w && cy < h {
                    let i = cy as usize * self.image.width + cx as usize;
                    if self.image.cells[i] == UNKNOWN {
                        self.image.cells[i] = FREE;
                        changed = true;
                    }
                }
            }
            if let Some(i) = self.cell(end) {
                changed |= self.image.cells[i] != OCCUPIED;
                self.image.cells[i] = OCCUPIED;
            }
        }
        if changed {
            self.image.version += 1;
        }
    }

    /// The map as it stands, shared: publishing the same version again copies nothing.
    pub fn image(&mut self) -> Arc<OccupancyImage> {
        match &self.shared {
            Some(s) if s.version == self.image.version => s.clone(),
            _ => {
                let s = Arc::new(self.image.clone());
                self.shared = Some(s.clone());
                s
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_beam_frees_its_path_and_occupies_its_end() {
        let mut map = ScanMap::new([0.0, 0.0], 5.0);
        assert_eq!(map.image().resolution_m, FINEST_M);
        // Facing +y, a beam straight ahead (angle 0) ends 2 m up; invalid beams do nothing.
        let pose = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        map.add(pose, &[Beam::new(0.0, 2.0), Beam::invalid(1.0)]);
        let img = map.image();
        assert_eq!(img.version, 1);
        let at = |x: f64, y: f64| {
            let cx = ((x - img.origin_m[0]) / img.resolution_m) as usize;
            let cy = ((y - img.origin_m[1]) / img.resolution_m) as usize;
            img.cells[cy * img.width + cx]
        };
        assert_eq!(at(0.01, 2.01), OCCUPIED);
        assert_eq!(at(0.01, 1.0), FREE);
        assert_eq!(at(1.0, 0.01), UNKNOWN);
        // The same revolution again changes nothing, so the same image is handed out.
        map.add(pose, &[Beam::new(0.0, 2.0)]);
        assert!(Arc::ptr_eq(&img, &map.image()));
    }

    #[test]
    fn large_areas_get_coarser_cells_and_bad_input_is_ignored() {
        let mut map = ScanMap::new([0.0, 0.0], 200.0);
        let img = map.image();
        assert!(img.width <= MAX_SIDE_CELLS && img.resolution_m > FINEST_M);
        map.add([f64::NAN, 0.0, 0.0], &[Beam::new(0.0, 2.0)]);
        map.add([0.0, 0.0, 0.0], &[Beam::new(0.0, 1e9)]);
        assert!(map.image().is_consistent());
        let tiny = ScanMap::new([0.0, 0.0], f64::NAN).image();
        assert!(tiny.is_consistent());
    }
}
