//! What `plumbline slam` writes: the trajectory, the map files, the pose graph and the plot.

use super::SlamArgs;
use crate::odometry_cmd::write_file;
use crate::plot::plot_trajectory;
use crate::report::CliError;
use plumbline_core::geom::Pose2;
use plumbline_io::carmen::{LaserRecord, OdomPose};
use plumbline_io::trajectory::{write_trajectory, TrajectoryPoint};
use plumbline_slam::backend::Backend;
use plumbline_slam::graph::write_g2o;
use plumbline_slam::grid::{GridConfig, OccupancyGrid, Raster};
use plumbline_slam::map_files::write_map;
use std::ffi::OsString;
use std::path::PathBuf;

/// Beams are drawn into the map up to this range, m: farther returns are the noisiest, and the
/// map is for the rooms the vehicle flies through.
const MAP_RANGE_M: f32 = 25.0;

/// What was written, for the summary.
pub struct Written {
    pub grid: Option<OccupancyGrid>,
}

/// Where a scan sits in the graph: its keyframe (if any yet), its pose relative to it, and
/// whether that pose is a prediction (the match failed).
#[derive(Clone, Copy, Debug)]
pub struct Anchor {
    pub keyframe: Option<usize>,
    pub relative: Pose2,
    pub lost: bool,
}

/// Every scan's final pose: its keyframe's optimised pose composed with the tracked motion from
/// that keyframe (scans before the first keyframe keep the tracker's pose). Predicted poses are
/// marked lost, so the trajectory file says which poses are not measurements.
pub fn trajectory(
    scans: &[LaserRecord],
    anchors: &[Anchor],
    keyframe_poses: &[Pose2],
) -> Vec<TrajectoryPoint> {
    scans
        .iter()
        .zip(anchors)
        .map(|(rec, a)| TrajectoryPoint {
            timestamp_text: rec.timestamp_text.clone(),
            timestamp_s: rec.timestamp_s,
            pose: OdomPose::from_f32(
                a.keyframe
                    .map_or(a.relative, |k| keyframe_poses[k].compose(a.relative)),
            ),
            lost: a.lost,
        })
        .collect()
}

/// The occupancy grid of every keyframe that kept its scan, at its optimised pose.
pub fn grid<const N: usize>(backend: &Backend<N>) -> Result<OccupancyGrid, CliError> {
    let mut grid =
        OccupancyGrid::new(GridConfig::default()).map_err(|e| CliError(format!("map: {e:?}")))?;
    for (keyframe, &pose) in backend.keyframes().iter().zip(backend.poses()) {
        if keyframe.has_scan() {
            grid.insert_scan(pose, &keyframe.beams, MAP_RANGE_M)
                .map_err(|e| CliError(format!("map: {e:?}")))?;
        }
    }
    Ok(grid)
}

pub fn write<const N: usize>(
    args: &SlamArgs,
    scans: &[LaserRecord],
    trajectory: &[TrajectoryPoint],
    backend: &Backend<N>,
) -> Result<Written, CliError> {
    if let Some(path) = &args.out {
        write_file(path, |w| write_trajectory(w, trajectory))?;
    }
    let mut written = Written { grid: None };
    if let Some(prefix) = &args.map {
        let grid = grid(backend)?;
        let raster = Raster::from_grid(&grid)
            .map_err(|e| CliError(format!("map: {e:?}")))?
            .ok_or_else(|| CliError("map: no keyframe put anything on the map".into()))?;
        let path: Vec<Pose2> = trajectory.iter().map(|t| t.pose.to_f32()).collect();
        write_map(prefix, &raster, &path)?;
        let mut g2o = OsString::from(prefix.as_os_str());
        g2o.push(".g2o");
        write_file(&PathBuf::from(g2o), |w| write_g2o(backend.graph(), w))?;
        written.grid = Some(grid);
    }
    if let Some(path) = &args.plot {
        plot_trajectory(path, scans, trajectory)
            .map_err(|e| CliError(format!("{}: {e}", path.display())))?;
    }
    Ok(written)
}
