//! The map as files people and tools open: the ROS map_server pair `PREFIX.pgm` +
//! `PREFIX.yaml` (what map_server, nav2 and RViz load) and `PREFIX.png` in seed 002 Fig. 7's
//! style with the path on top. All three come from one [`Raster`], so they align pixel for
//! pixel. [`check_writable`] lets a command fail on a bad prefix before it spends minutes on a
//! log.

mod map_server;
mod picture;

pub use map_server::{pgm_bytes, yaml_text, PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN};
pub use picture::{png_rgb, PATH_RGB, POSE_RGB};

use crate::grid::Raster;
use plumbline_core::geom::Pose2;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// A map file could not be written: the path and what went wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct MapFileError {
    pub path: PathBuf,
    pub reason: String,
}

impl core::fmt::Display for MapFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.reason)
    }
}

impl std::error::Error for MapFileError {}

/// The three files of a map prefix.
#[derive(Clone, Debug, PartialEq)]
pub struct MapPaths {
    pub pgm: PathBuf,
    pub yaml: PathBuf,
    pub png: PathBuf,
}

impl MapPaths {
    /// `PREFIX.pgm`, `PREFIX.yaml`, `PREFIX.png` (the suffix is appended, so `maps/run.1`
    /// gives `maps/run.1.pgm`).
    pub fn of(prefix: &Path) -> MapPaths {
        let with = |ext: &str| {
            let mut s = OsString::from(prefix.as_os_str());
            s.push(ext);
            PathBuf::from(s)
        };
        MapPaths {
            pgm: with(".pgm"),
            yaml: with(".yaml"),
            png: with(".png"),
        }
    }

    fn all(&self) -> [&Path; 3] {
        [&self.pgm, &self.yaml, &self.png]
    }
}

/// Checks, without writing the map, that its three files can be created: the prefix names a
/// file in a directory that exists and accepts new files, and no target is a directory.
pub fn check_writable(prefix: &Path) -> Result<MapPaths, MapFileError> {
    let err = |path: &Path, reason: String| MapFileError {
        path: path.to_path_buf(),
        reason,
    };
    let name_ok = prefix
        .file_name()
        .is_some_and(|n| !n.is_empty() && n != "." && n != "..");
    if !name_ok || prefix.as_os_str().to_string_lossy().ends_with('/') {
        return Err(err(
            prefix,
            "the map prefix names no file: give DIR/NAME, which writes NAME.pgm, NAME.yaml and \
             NAME.png in DIR"
                .into(),
        ));
    }
    let dir = match prefix.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(err(dir, "is not a directory".into())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(err(
                dir,
                "directory does not exist: create it first, or choose another map prefix".into(),
            ))
        }
        Err(e) => return Err(err(dir, e.to_string())),
    }
    let paths = MapPaths::of(prefix);
    for p in paths.all() {
        if p.is_dir() {
            return Err(err(p, "is a directory, not a file".into()));
        }
    }
    // The one sure test of permission is to create a file; a uniquely named probe is removed
    // at once, and existing map files are left untouched until the map is written.
    let probe = dir.join(format!(".plumbline-write-test-{}", std::process::id()));
    std::fs::File::create(&probe)
        .map_err(|e| err(dir, format!("cannot create files here: {e}")))?;
    let _ = std::fs::remove_file(&probe);
    for p in paths.all() {
        if p.exists() {
            std::fs::OpenOptions::new()
                .write(true)
                .open(p)
                .map_err(|e| err(p, format!("exists and cannot be overwritten: {e}")))?;
        }
    }
    Ok(paths)
}

/// Writes `PREFIX.pgm`, `PREFIX.yaml` and `PREFIX.png` (with `path`, the poses in the map
/// frame, drawn as a polyline ending in a triangle at the last pose).
pub fn write_map(prefix: &Path, raster: &Raster, path: &[Pose2]) -> Result<MapPaths, MapFileError> {
    let paths = check_writable(prefix)?;
    let image_name = paths
        .pgm
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let write = |p: &Path, bytes: &[u8]| {
        std::fs::write(p, bytes).map_err(|e| MapFileError {
            path: p.to_path_buf(),
            reason: e.to_string(),
        })
    };
    write(&paths.pgm, &pgm_bytes(raster))?;
    write(&paths.yaml, yaml_text(&image_name, raster).as_bytes())?;
    let png = png_rgb(raster, path).map_err(|e| MapFileError {
        path: paths.png.clone(),
        reason: e,
    })?;
    write(&paths.png, &png)?;
    Ok(paths)
}
