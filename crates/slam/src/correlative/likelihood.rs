//! The likelihood grid a correlative search scores against: each reference point stamps a
//! Gaussian of the distance to it, one byte a cell, and each pyramid level holds the largest
//! value of a block of the level below, the bound branch and bound prunes with.

use super::{CorrelativeConfig, LookupGrid};
use plumbline_core::geom::Vec2;

/// Cells the stamping kernel reaches on each side of its centre.
pub(super) const KERNEL_CELLS: i32 = 3;

impl LookupGrid {
    /// Builds the grid over the points' bounding box plus `margin_m` (the farthest a searched
    /// scan may reach past the reference).
    pub fn new(points: &[Vec2], margin_m: f32, config: &CorrelativeConfig, levels: usize) -> Self {
        let res = config.resolution_m;
        let (mut lo, mut hi) = (Vec2::new(f32::MAX, f32::MAX), Vec2::new(f32::MIN, f32::MIN));
        for p in points.iter().filter(|p| p.is_finite()) {
            lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        if lo.x > hi.x {
            lo = Vec2::ZERO;
            hi = Vec2::ZERO;
        }
        let origin = Vec2::new(lo.x - margin_m, lo.y - margin_m);
        let width = (((hi.x - lo.x + 2.0 * margin_m) / res).ceil() as i32 + 1).max(1);
        let height = (((hi.y - lo.y + 2.0 * margin_m) / res).ceil() as i32 + 1).max(1);
        let mut base = vec![0u8; (width * height) as usize];
        let kernel = gaussian_kernel(res, config.sigma_m);
        let side = (2 * KERNEL_CELLS + 1) as usize;
        // Points in one cell stamp the same kernel, so only the first of them needs to. When
        // the kernel reaches its peak at its centre alone, a cell holding the peak is the
        // centre of a kernel already stamped: the scans of a keyframe and its neighbours put
        // several points in most cells they see.
        let peak = u8::MAX;
        let centre_alone =
            kernel.iter().filter(|&&v| v == peak).count() == 1 && kernel[side * side / 2] == peak;
        for p in points.iter().filter(|p| p.is_finite()) {
            let cx = ((p.x - origin.x) / res) as i32;
            let cy = ((p.y - origin.y) / res) as i32;
            let stamped = centre_alone
                && (0..width).contains(&cx)
                && (0..height).contains(&cy)
                && base[(cy * width + cx) as usize] == peak;
            if stamped {
                continue;
            }
            // The kernel's columns and rows that land on the grid.
            let (x0, x1) = (
                cx.saturating_sub(KERNEL_CELLS).max(0),
                cx.saturating_add(KERNEL_CELLS).min(width - 1),
            );
            let (y0, y1) = (
                cy.saturating_sub(KERNEL_CELLS).max(0),
                cy.saturating_add(KERNEL_CELLS).min(height - 1),
            );
            if x0 > x1 {
                continue;
            }
            let kx = (x0 - (cx - KERNEL_CELLS)) as usize;
            let columns = (x1 - x0 + 1) as usize;
            for y in y0..=y1 {
                let ky = (y - (cy - KERNEL_CELLS)) as usize;
                let weights = &kernel[ky * side + kx..][..columns];
                let start = (y * width + x0) as usize;
                for (cell, &v) in base[start..start + columns].iter_mut().zip(weights) {
                    *cell = (*cell).max(v);
                }
            }
        }
        let mut levels_built = vec![base];
        for k in 1..levels.max(1) {
            let next = block_max(&levels_built[k - 1], width as usize, 1 << (k - 1));
            levels_built.push(next);
        }
        Self {
            origin,
            resolution: res,
            width,
            height,
            levels: levels_built,
        }
    }
}

/// The next pyramid level of `prev` (rows of `width` cells): each cell the largest of itself
/// and the cells `step` to its right, above it and both, cells past the far edges counting as
/// 0. A maximum splits into one along rows and one along columns, and each runs over whole
/// rows at once.
fn block_max(prev: &[u8], width: usize, step: usize) -> Vec<u8> {
    let mut next = prev.to_vec();
    // Along rows: cell x takes the larger of itself and cell x + step of the same row.
    if step < width {
        for (row, old) in next.chunks_exact_mut(width).zip(prev.chunks_exact(width)) {
            for (cell, &right) in row.iter_mut().zip(&old[step..]) {
                *cell = (*cell).max(right);
            }
        }
    }
    // Along columns: row y takes the larger of itself and row y + step (not yet changed).
    let rows = next.len() / width.max(1);
    for y in 0..rows.saturating_sub(step) {
        let (low, high) = next.split_at_mut((y + step) * width);
        for (cell, &up) in low[y * width..].iter_mut().zip(&high[..width]) {
            *cell = (*cell).max(up);
        }
    }
    next
}

/// Likelihood of a point at each offset of the stamping kernel, 0 to 255.
pub(super) fn gaussian_kernel(resolution: f32, sigma: f32) -> Vec<u8> {
    let side = 2 * KERNEL_CELLS + 1;
    let mut k = Vec::with_capacity((side * side) as usize);
    for dy in -KERNEL_CELLS..=KERNEL_CELLS {
        for dx in -KERNEL_CELLS..=KERNEL_CELLS {
            let d2 = ((dx * dx + dy * dy) as f32) * resolution * resolution;
            let v = (-d2 / (2.0 * sigma * sigma)).exp();
            k.push((v * 255.0).round() as u8);
        }
    }
    k
}
