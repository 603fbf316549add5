//! The map_server pair: a binary PGM and its YAML, by the rules map_server (ROS 1) and nav2's
//! map_server (ROS 2) load them with `negate: 0` and `mode: trinary`: a pixel's occupancy is
//! `p = (255 - value) / 255`; `p > occupied_thresh` is occupied, `p < free_thresh` is free,
//! anything between is unknown. The three values written are the ones map_saver writes.

use crate::grid::{CellState, Raster};

/// Occupied: p = 1.
pub const PGM_OCCUPIED: u8 = 0;
/// Free: p = 1/255, below `free_thresh`.
pub const PGM_FREE: u8 = 254;
/// Unknown: p = 50/255 = 0.19608, just above `free_thresh` 0.196 and below 0.65.
pub const PGM_UNKNOWN: u8 = 205;

/// The raster as a binary (P5) PGM, row 0 at the top, as map_server expects.
pub fn pgm_bytes(raster: &Raster) -> Vec<u8> {
    let mut out = format!("P5\n{} {}\n255\n", raster.width, raster.height).into_bytes();
    out.extend(raster.states.iter().map(|s| match s {
        CellState::Occupied => PGM_OCCUPIED,
        CellState::Free => PGM_FREE,
        CellState::Unknown => PGM_UNKNOWN,
    }));
    out
}

/// The YAML beside the PGM. `image` is relative to the YAML's directory (map_server resolves
/// it so) and quoted, so names with spaces, colons or `#` stay one string. `origin` is the
/// map-frame pose of the lower-left pixel's corner; no rotation.
pub fn yaml_text(image_name: &str, raster: &Raster) -> String {
    let quoted = image_name.replace('\\', "\\\\").replace('"', "\\\"");
    let [x, y] = raster.origin_m();
    format!(
        "image: \"{quoted}\"\nresolution: {}\norigin: [{x:.6}, {y:.6}, 0.0]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
        raster.resolution_m()
    )
}
