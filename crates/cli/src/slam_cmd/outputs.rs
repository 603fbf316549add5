//! What `plumbline slam` writes: the trajectory, the map files, the pose graph and the plot.

use crate::plot::{plot_trajectory, stage_png, write_png, PlotScans};
use crate::report::CliError;
use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_io::carmen::OdomPose;
use plumbline_io::output::OutputFile;
use plumbline_io::trajectory::{write_trajectory, TrajectoryPoint};
use plumbline_slam::backend::Backend;
use plumbline_slam::deskew::{deskew, MotionHistory};
use plumbline_slam::graph::write_g2o;
use plumbline_slam::grid::{GridConfig, OccupancyGrid, PreparedScan, Raster};
use plumbline_slam::map_files::write_map;
use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Beams are drawn into the map up to this range, m: farther returns are the noisiest, and the
/// map is for the rooms the vehicle flies through.
const MAP_RANGE_M: f32 = 25.0;

/// A map cell with at most this many hits is cleared by the scans that see through it (see
/// [`OccupancyGrid::see_through`]): a person walking past leaves one or two hits a cell in the
/// keyframe that caught them (simulated office surveys: 45 such cells a survey, each with one or
/// two hits and no miss), while a wall seen from several keyframes has more.
const TRANSIENT_MAX_HITS: u16 = 2;

/// The beams of every tracked scan, kept (in the sensor frame, de-skewed like the tracker's)
/// until the final poses are known, so that the map can let them see through what a keyframe
/// caught in passing. Each scan costs 8 bytes a beam; nothing is kept when no map is wanted.
pub struct SeenThrough<const N: usize> {
    history: MotionHistory,
    fixed: Box<Scan<N>>,
    scans: Vec<PreparedScan>,
}

impl<const N: usize> SeenThrough<N> {
    pub fn new() -> Self {
        Self {
            history: MotionHistory::default(),
            fixed: Box::default(),
            scans: Vec::new(),
        }
    }

    /// Keeps `scan`'s beams, de-skewed at the rate of the recent poses when `deskew_beams` (the
    /// tracker's own rule without a motion prior), and notes `pose` (the scan's map-frame pose
    /// as known now) for the next one. `map_jumped`: a loop closure moved the map since the
    /// last scan, so the poses before it would give a false rate and are forgotten.
    pub fn add(&mut self, scan: &Scan<N>, pose: Pose2, deskew_beams: bool, map_jumped: bool) {
        if map_jumped {
            self.history = MotionHistory::default();
        }
        let beams = match self.history.rate().filter(|_| deskew_beams) {
            Some(motion) => {
                deskew(scan, motion, &mut self.fixed);
                self.fixed.beams()
            }
            None => scan.beams(),
        };
        // MAP_RANGE_M is finite and positive and no clearing range is given: cannot fail.
        self.scans
            .push(PreparedScan::from_beams(beams, MAP_RANGE_M, None).unwrap_or_default());
        self.history.push(scan.stamp_s, pose);
    }
}

/// What was written, for the summary.
pub struct Written {
    pub grid: Option<OccupancyGrid>,
}

/// Where a scan sits in the graph: its time, its keyframe (if any yet), its pose relative to
/// it, and whether that pose is a prediction (the match failed). All a scan leaves behind once
/// it has been tracked, so memory grows by a few dozen bytes a scan, not by the scan.
#[derive(Clone, Debug)]
pub struct Anchor {
    pub timestamp_text: String,
    pub timestamp_s: f64,
    pub keyframe: Option<usize>,
    pub relative: Pose2,
    pub lost: bool,
}

/// Every scan's final pose: its keyframe's optimised pose composed with the tracked motion from
/// that keyframe (scans before the first keyframe keep the tracker's pose). Predicted poses are
/// marked lost, so the trajectory file says which poses are not measurements.
pub fn trajectory(anchors: Vec<Anchor>, keyframe_poses: &[Pose2]) -> Vec<TrajectoryPoint> {
    anchors
        .into_iter()
        .map(|a| TrajectoryPoint {
            pose: OdomPose::from_f32(
                a.keyframe
                    .map_or(a.relative, |k| keyframe_poses[k].compose(a.relative)),
            ),
            timestamp_text: a.timestamp_text,
            timestamp_s: a.timestamp_s,
            lost: a.lost,
        })
        .collect()
}

/// The occupancy grid of every keyframe that kept its scan, at its optimised pose; then every
/// scan with a measured pose in `trajectory` sees through the cells of `seen` (one prepared scan
/// per trajectory point) that a keyframe hit at most [`TRANSIENT_MAX_HITS`] times.
pub fn grid<const N: usize>(
    backend: &Backend<N>,
    trajectory: &[TrajectoryPoint],
    seen: &SeenThrough<N>,
) -> Result<OccupancyGrid, CliError> {
    let mut grid =
        OccupancyGrid::new(GridConfig::default()).map_err(|e| CliError(format!("map: {e:?}")))?;
    for (keyframe, &pose) in backend.keyframes().iter().zip(backend.poses()) {
        if keyframe.has_scan() {
            grid.insert_scan(pose, &keyframe.beams, MAP_RANGE_M)
                .map_err(|e| CliError(format!("map: {e:?}")))?;
        }
    }
    for (point, scan) in trajectory.iter().zip(&seen.scans) {
        if !point.lost {
            grid.see_through(point.pose.to_f32(), scan, TRANSIENT_MAX_HITS)
                .map_err(|e| CliError(format!("map: {e:?}")))?;
        }
    }
    Ok(grid)
}

/// The files `--out`, `--plot` and the pose graph beside `--map`, staged before the work so an
/// unwritable one is reported first; each replaces its old file only once it is complete.
pub struct Staged {
    trajectory: Option<OutputFile>,
    plot: Option<OutputFile>,
    g2o: Option<OutputFile>,
}

/// `PREFIX.g2o`, the pose graph written beside the map files.
pub fn g2o_path(prefix: &Path) -> PathBuf {
    let mut g2o = OsString::from(prefix.as_os_str());
    g2o.push(".g2o");
    PathBuf::from(g2o)
}

impl Staged {
    pub fn new(
        out: Option<&Path>,
        plot: Option<&Path>,
        map: Option<&Path>,
    ) -> Result<Self, CliError> {
        Ok(Self {
            trajectory: out.map(OutputFile::stage).transpose()?,
            plot: plot.map(|p| stage_png("--plot", p)).transpose()?,
            g2o: map.map(|m| OutputFile::stage(&g2o_path(m))).transpose()?,
        })
    }

    pub fn write<const N: usize>(
        self,
        map: Option<&Path>,
        plot_scans: Option<PlotScans>,
        trajectory: &[TrajectoryPoint],
        seen: &SeenThrough<N>,
        backend: &Backend<N>,
    ) -> Result<Written, CliError> {
        if let Some(mut w) = self.trajectory {
            write_trajectory(&mut w, trajectory).map_err(|e| w.error(e))?;
            w.commit()?;
        }
        let mut written = Written { grid: None };
        if let Some(prefix) = map {
            let grid = grid(backend, trajectory, seen)?;
            let raster = Raster::from_grid(&grid)
                .map_err(|e| CliError(format!("map: {e:?}")))?
                .ok_or_else(|| CliError("map: no keyframe put anything on the map".into()))?;
            let path: Vec<Pose2> = trajectory.iter().map(|t| t.pose.to_f32()).collect();
            write_map(prefix, &raster, &path)?;
            written.grid = Some(grid);
        }
        if let Some(mut w) = self.g2o {
            write_g2o(backend.graph(), &mut w)
                .and_then(|()| w.flush())
                .map_err(|e| w.error(e))?;
            w.commit()?;
        }
        if let (Some(out), Some(scans)) = (self.plot, plot_scans) {
            let data = scans.place(trajectory);
            write_png(out, |p| plot_trajectory(p, &data))?;
        }
        Ok(written)
    }
}
