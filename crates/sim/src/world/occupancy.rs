//! Worlds from occupancy grids: a PGM image (ROS `map_server` convention) or laser hits
//! gathered along a logged trajectory. Walls are the boundaries between occupied and free
//! cells, merged into straight runs so a building becomes thousands of walls, not millions.

use crate::world::{Segment, World, WorldError};

/// Most cells a rasterised grid may have: 16 million (64 MB of hit counts), 400 m x 400 m at
/// 0.1 m. Larger extents come from bad poses, not from buildings.
pub const MAX_RASTER_CELLS: usize = 16_000_000;

/// Why laser hits could not be rasterised.
#[derive(Clone, Debug, PartialEq)]
pub enum RasterError {
    NoPoints,
    /// The points span `extent_m` (x, y), which needs `cells` cells (NaN for non-finite points).
    TooLarge {
        extent_m: [f64; 2],
        cells: f64,
    },
}

impl std::fmt::Display for RasterError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RasterError::NoPoints => f.write_str("no laser hits to rasterise"),
            RasterError::TooLarge { extent_m, cells } => write!(
                f,
                "the laser hits span {:.0} m x {:.0} m ({cells:.3e} cells), more than the {MAX_RASTER_CELLS} a grid may have",
                extent_m[0], extent_m[1]
            ),
        }
    }
}

/// Occupied cells on a regular grid; row 0 is the lowest y.
#[derive(Clone, Debug, PartialEq)]
pub struct Occupancy {
    pub width: usize,
    pub height: usize,
    pub resolution_m: f64,
    /// World position of the lower-left corner of cell (0, 0), m.
    pub origin: [f64; 2],
    pub occupied: Vec<bool>,
}

fn pgm_error(reason: impl Into<String>) -> WorldError {
    WorldError {
        line: 0,
        reason: reason.into(),
    }
}

impl Occupancy {
    fn at(&self, i: isize, j: isize) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.width
            && (j as usize) < self.height
            && self.occupied[j as usize * self.width + i as usize]
    }

    /// Cells hit at least `min_hits` times by the points (m); a grid just covering them. An
    /// error when there is nothing to rasterise or the grid would exceed [`MAX_RASTER_CELLS`]
    /// (points far apart, or not finite, are a bad input, not a building).
    pub fn from_hits(
        points: &[[f64; 2]],
        resolution_m: f64,
        min_hits: u32,
    ) -> Result<Occupancy, RasterError> {
        let (x0, y0, x1, y1) = points.iter().fold(
            (f64::MAX, f64::MAX, f64::MIN, f64::MIN),
            |(a, b, c, d), p| (a.min(p[0]), b.min(p[1]), c.max(p[0]), d.max(p[1])),
        );
        if points.is_empty() {
            return Err(RasterError::NoPoints);
        }
        let origin = [x0 - resolution_m, y0 - resolution_m];
        let cells_x = ((x1 - origin[0]) / resolution_m).ceil() + 2.0;
        let cells_y = ((y1 - origin[1]) / resolution_m).ceil() + 2.0;
        let finite = points.iter().all(|p| p[0].is_finite() && p[1].is_finite());
        let cells = if finite { cells_x * cells_y } else { f64::NAN };
        if !(resolution_m > 0.0 && cells <= MAX_RASTER_CELLS as f64) {
            return Err(RasterError::TooLarge {
                extent_m: [x1 - x0, y1 - y0],
                cells,
            });
        }
        let (width, height) = (cells_x as usize, cells_y as usize);
        let mut hits = vec![0u32; width * height];
        for p in points {
            let i = ((p[0] - origin[0]) / resolution_m) as usize;
            let j = ((p[1] - origin[1]) / resolution_m) as usize;
            hits[j * width + i] += 1;
        }
        Ok(Occupancy {
            width,
            height,
            resolution_m,
            origin,
            occupied: hits.iter().map(|&h| h >= min_hits).collect(),
        })
    }

    /// Reads a binary (P5) or text (P2) PGM; pixels darker than half the maximum are occupied
    /// (map_server: black is occupied, white free, grey unknown counts as free).
    pub fn from_pgm(
        bytes: &[u8],
        resolution_m: f64,
        origin: [f64; 2],
    ) -> Result<Occupancy, WorldError> {
        let binary = bytes.starts_with(b"P5");
        if !binary && !bytes.starts_with(b"P2") {
            return Err(pgm_error("not a PGM image (expected P5 or P2)"));
        }
        // Header: magic, width, height, maxval, separated by whitespace, `#` comments allowed.
        let mut pos = 2;
        let mut fields = [0usize; 3];
        for f in &mut fields {
            loop {
                while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
                    pos += 1;
                }
                if bytes.get(pos) == Some(&b'#') {
                    while pos < bytes.len() && bytes[pos] != b'\n' {
                        pos += 1;
                    }
                } else {
                    break;
                }
            }
            let start = pos;
            while pos < bytes.len() && bytes[pos].is_ascii_digit() {
                pos += 1;
            }
            *f = std::str::from_utf8(&bytes[start..pos])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| pgm_error("bad PGM header"))?;
        }
        let [width, height, maxval] = fields;
        if width == 0 || height == 0 || maxval == 0 || maxval > 255 {
            return Err(pgm_error(format!(
                "unsupported PGM: {width}x{height}, maxval {maxval}"
            )));
        }
        let pixels: Vec<usize> = if binary {
            let data = bytes
                .get(pos + 1..pos + 1 + width * height)
                .ok_or_else(|| pgm_error("PGM data is shorter than width x height"))?;
            data.iter().map(|&b| b as usize).collect()
        } else {
            let text =
                std::str::from_utf8(&bytes[pos..]).map_err(|_| pgm_error("P2 data is not text"))?;
            let v: Vec<usize> = text
                .split_ascii_whitespace()
                .map(|s| s.parse().map_err(|_| pgm_error(format!("bad pixel `{s}`"))))
                .collect::<Result<_, _>>()?;
            if v.len() < width * height {
                return Err(pgm_error("PGM data is shorter than width x height"));
            }
            v
        };
        if !(resolution_m > 0.0 && resolution_m.is_finite()) {
            return Err(pgm_error("resolution must be positive"));
        }
        // Image row 0 is the top (largest y).
        let occupied = (0..height)
            .flat_map(|j| (0..width).map(move |i| (i, height - 1 - j)))
            .map(|(i, r)| pixels[r * width + i] * 2 < maxval)
            .collect();
        Ok(Occupancy {
            width,
            height,
            resolution_m,
            origin,
            occupied,
        })
    }

    /// A binary PGM of the grid (black occupied, white free), top row first.
    pub fn to_pgm(&self) -> Vec<u8> {
        let mut out = format!("P5\n{} {}\n255\n", self.width, self.height).into_bytes();
        for j in (0..self.height).rev() {
            out.extend((0..self.width).map(|i| {
                if self.occupied[j * self.width + i] {
                    0u8
                } else {
                    254
                }
            }));
        }
        out
    }

    /// Boundaries between occupied and free cells, merged along rows and columns.
    pub fn walls(&self) -> Vec<Segment> {
        let r = self.resolution_m;
        let [ox, oy] = self.origin;
        let mut walls = Vec::new();
        // Horizontal edges between rows j-1 and j, and vertical edges between columns i-1 and i.
        for j in 0..=self.height as isize {
            let mut run: Option<isize> = None;
            for i in 0..=self.width as isize {
                let edge = i < self.width as isize && self.at(i, j - 1) != self.at(i, j);
                match (edge, run) {
                    (true, None) => run = Some(i),
                    (false, Some(s)) => {
                        let y = oy + j as f64 * r;
                        walls.push(Segment::new([ox + s as f64 * r, y], [ox + i as f64 * r, y]));
                        run = None;
                    }
                    _ => {}
                }
            }
        }
        for i in 0..=self.width as isize {
            let mut run: Option<isize> = None;
            for j in 0..=self.height as isize {
                let edge = j < self.height as isize && self.at(i - 1, j) != self.at(i, j);
                match (edge, run) {
                    (true, None) => run = Some(j),
                    (false, Some(s)) => {
                        let x = ox + i as f64 * r;
                        walls.push(Segment::new([x, oy + s as f64 * r], [x, oy + j as f64 * r]));
                        run = None;
                    }
                    _ => {}
                }
            }
        }
        walls
    }
}

/// Grids become worlds here, not in `world`, so that the world format does not depend on the
/// grid (the grid's wall tracing uses the world's segments).
impl World {
    /// A world whose walls outline an occupancy grid's occupied cells.
    pub fn from_occupancy(
        name: &str,
        grid: &Occupancy,
        start: [f64; 3],
        path: Vec<[f64; 2]>,
        altitude_m: f64,
        ceiling_m: f64,
    ) -> World {
        World {
            name: name.into(),
            ceiling_m,
            start,
            walls: grid.walls(),
            blocks: Vec::new(),
            path,
            altitude_m,
            walkers: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_block_becomes_four_walls() {
        let mut occ = Occupancy {
            width: 5,
            height: 4,
            resolution_m: 0.5,
            origin: [1.0, 2.0],
            occupied: vec![false; 20],
        };
        for (i, j) in [(1, 1), (2, 1), (1, 2), (2, 2)] {
            occ.occupied[j * 5 + i] = true;
        }
        let mut walls = occ.walls();
        walls.sort_by(|a, b| a.a.partial_cmp(&b.a).unwrap());
        assert_eq!(walls.len(), 4, "{walls:?}");
        assert!(walls.contains(&Segment::new([1.5, 2.5], [2.5, 2.5])));
        assert!(walls.contains(&Segment::new([2.5, 2.5], [2.5, 3.5])));
    }

    #[test]
    fn pgm_round_trip_keeps_the_grid_and_flips_rows() {
        let mut occ = Occupancy {
            width: 3,
            height: 2,
            resolution_m: 0.1,
            origin: [0.0, 0.0],
            occupied: vec![false; 6],
        };
        occ.occupied[5] = true; // top-right cell
        let bytes = occ.to_pgm();
        assert_eq!(
            bytes[bytes.len() - 4],
            0,
            "first data row is the top row: its last pixel is black"
        );
        assert_eq!(Occupancy::from_pgm(&bytes, 0.1, [0.0, 0.0]).unwrap(), occ);
        let text = b"P2\n# a comment\n3 2\n255\n255 255 0\n255 255 255\n";
        assert_eq!(Occupancy::from_pgm(text, 0.1, [0.0, 0.0]).unwrap(), occ);
        assert!(Occupancy::from_pgm(b"P6\n1 1\n255\n", 0.1, [0.0, 0.0])
            .unwrap_err()
            .reason
            .contains("not a PGM"));
        assert!(Occupancy::from_pgm(b"P5\n4 4\n255\n\x00", 0.1, [0.0, 0.0])
            .unwrap_err()
            .reason
            .contains("shorter"));
    }

    #[test]
    fn hits_below_the_threshold_are_ignored() {
        let pts = [[0.05, 0.05], [0.06, 0.04], [1.05, 0.05]];
        let occ = Occupancy::from_hits(&pts, 0.1, 2).unwrap();
        for far in [1e7, 1e30, f64::NAN] {
            let mut with = pts.to_vec();
            with.push([far, 0.0]);
            assert!(matches!(
                Occupancy::from_hits(&with, 0.1, 2),
                Err(RasterError::TooLarge { .. })
            ));
        }
        assert_eq!(
            Occupancy::from_hits(&[], 0.1, 2),
            Err(RasterError::NoPoints)
        );
        assert_eq!(occ.occupied.iter().filter(|&&o| o).count(), 1);
    }
}
