//! The map for people, in seed 002 Fig. 7's style: free space light, obstacles dark,
//! unexplored grey, the path flown on top and a triangle at the last pose showing the heading.
//! One pixel per cell, from the same raster as the PGM.

use crate::grid::{trace, Cell, CellState, Raster};
use plumbline_core::geom::{Pose2, Vec2};

/// Path colour (blue: stands out against every grey).
pub const PATH_RGB: [u8; 3] = [30, 90, 230];
/// Last-pose triangle colour (green, as in Fig. 7).
pub const POSE_RGB: [u8; 3] = [20, 170, 60];

const FREE_RGB: [u8; 3] = [250, 250, 250];
const OCCUPIED_RGB: [u8; 3] = [25, 25, 25];
const UNKNOWN_RGB: [u8; 3] = [160, 160, 160];

/// The picture as PNG bytes (8-bit RGB).
pub fn png_rgb(raster: &Raster, path: &[Pose2]) -> Result<Vec<u8>, String> {
    let mut rgb: Vec<u8> = raster
        .states
        .iter()
        .flat_map(|s| match s {
            CellState::Free => FREE_RGB,
            CellState::Occupied => OCCUPIED_RGB,
            CellState::Unknown => UNKNOWN_RGB,
        })
        .collect();
    let mut put = |(col, row): (i64, i64), c: [u8; 3]| {
        if (0..raster.width as i64).contains(&col) && (0..raster.height as i64).contains(&row) {
            let k = 3 * (row as usize * raster.width + col as usize);
            rgb[k..k + 3].copy_from_slice(&c);
        }
    };
    // Segments far outside the picture (a diverged pose) are skipped rather than walked.
    let reach = 2 * (raster.width + raster.height) as i64;
    let near = |(c, r): (i64, i64)| c.abs() <= reach && r.abs() <= reach;
    let pixel = |p: &Pose2| p.is_finite().then(|| raster.pixel_of(p.translation()));
    for w in path.windows(2) {
        if let (Some(a), Some(b)) = (pixel(&w[0]), pixel(&w[1])) {
            if near(a) && near(b) {
                let cell = |(c, r): (i64, i64)| Cell::new(c as i32, r as i32);
                trace(cell(a), cell(b), |c| {
                    put((c.i.into(), c.j.into()), PATH_RGB)
                });
                put(b, PATH_RGB);
            }
        }
    }
    if let Some(last) = path.last().filter(|p| p.is_finite()) {
        heading_triangle(raster, *last, |px| put(px, POSE_RGB));
    }
    encode(raster.width, raster.height, &rgb)
}

/// Fills a triangle 0.5 m long (at least 7 pixels) pointing along the pose's heading.
fn heading_triangle(raster: &Raster, pose: Pose2, mut put: impl FnMut((i64, i64))) {
    let len = (0.5 / raster.resolution_m()).max(7.0);
    let corners = [(0.6, 0.0), (-0.4, 0.35), (-0.4, -0.35)]
        .map(|(u, v)| pose.rotate(Vec2::new(u, v)) * (len * raster.resolution_m()));
    let (centre_col, centre_row) = raster.pixel_of(pose.translation());
    let res = raster.resolution_m();
    // Corners in pixel units, rows growing downwards.
    let px = corners.map(|c| (c.x / res, -c.y / res));
    let inside = |x: f32, y: f32| {
        let side = |a: (f32, f32), b: (f32, f32)| (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0);
        let s = [side(px[0], px[1]), side(px[1], px[2]), side(px[2], px[0])];
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    };
    let r = len.ceil() as i64;
    for dr in -r..=r {
        for dc in -r..=r {
            if inside(dc as f32, dr as f32) {
                put((centre_col + dc, centre_row + dr));
            }
        }
    }
}

fn encode(width: usize, height: usize, rgb: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, width as u32, height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    w.write_image_data(rgb).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())?;
    Ok(out)
}
