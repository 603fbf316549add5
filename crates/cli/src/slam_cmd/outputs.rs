//! What `plumbline slam` writes: the trajectory, the map files, the pose graph and the plot.

use crate::plot::{plot_trajectory, stage_png, write_png, PlotScans};
use crate::report::CliError;
use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_io::carmen::OdomPose;
use plumbline_io::output::OutputFile;
use plumbline_io::trajectory::{write_trajectory, TrajectoryPoint};
use plumbline_slam::backend::Backend;
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

/// Scans kept to see through the map are at least this far apart, s: the XV-11's 5 Hz rate,
/// which clears a passer-by in the simulated office surveys; a faster lidar's scans between
/// add little and would cost memory (8 bytes a beam: a 40 Hz UTM-30LX would keep 350 kB/s).
const SEEN_THROUGH_INTERVAL_S: f64 = 0.2;

/// Most heap bytes the kept scans may hold (about 1.5 hours of XV-11 scans at 5 Hz). A longer
/// log drops every other kept scan and keeps them twice as far apart from then on, so memory
/// stays bounded however long the log; a passer-by is then cleared by fewer scans.
const SEEN_THROUGH_MAX_BYTES: usize = 64 << 20;

/// The beams of tracked scans (in the sensor frame, as the tracker matched them), kept until
/// the final poses are known so that the map can let them see through what a keyframe caught in
/// passing; nothing is kept when no map is wanted.
pub struct SeenThrough<const N: usize> {
    /// (index of the scan in the log, its beams).
    scans: Vec<(usize, PreparedScan)>,
    /// Heap bytes of `scans`' beams, and the most they may hold.
    bytes: usize,
    max_bytes: usize,
    /// Least time between kept scans, s: [`SEEN_THROUGH_INTERVAL_S`], doubled at each thinning.
    interval_s: f64,
    /// Scans offered so far, and the stamp of the last one kept.
    offered: usize,
    last_kept_s: Option<f64>,
}

impl<const N: usize> SeenThrough<N> {
    pub fn new() -> Self {
        Self::within(SEEN_THROUGH_MAX_BYTES)
    }

    fn within(max_bytes: usize) -> Self {
        Self {
            scans: Vec::new(),
            bytes: 0,
            max_bytes,
            interval_s: SEEN_THROUGH_INTERVAL_S,
            offered: 0,
            last_kept_s: None,
        }
    }

    /// Keeps the beams of `scan` (as the tracker matched it) when the last kept scan is at least
    /// the interval between kept scans before it.
    pub fn add(&mut self, scan: &Scan<N>) {
        let index = self.offered;
        self.offered += 1;
        let due = self
            .last_kept_s
            .is_none_or(|t| (scan.stamp_s - t).abs() >= self.interval_s);
        if due {
            let beams = scan.beams();
            // MAP_RANGE_M is finite and positive and no clearing range is given: cannot fail.
            let prepared = PreparedScan::from_beams(beams, MAP_RANGE_M, None).unwrap_or_default();
            self.bytes += prepared.memory_bytes();
            self.scans.push((index, prepared));
            self.last_kept_s = Some(scan.stamp_s);
            if self.bytes > self.max_bytes {
                self.thin();
            }
        }
    }

    /// Drops every other kept scan and doubles the interval between the next ones.
    fn thin(&mut self) {
        let mut k = 0;
        self.scans.retain(|_| {
            k += 1;
            k % 2 == 1
        });
        self.bytes = self.scans.iter().map(|(_, s)| s.memory_bytes()).sum();
        self.interval_s *= 2.0;
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
/// scan kept in `seen` whose pose in `trajectory` is measured sees through the cells a keyframe
/// hit at most [`TRANSIENT_MAX_HITS`] times.
pub fn grid<const N: usize>(
    backend: &Backend<N>,
    trajectory: &[TrajectoryPoint],
    seen: &SeenThrough<N>,
) -> Result<OccupancyGrid, CliError> {
    let mut grid =
        OccupancyGrid::new(GridConfig::default()).map_err(|e| CliError(format!("map: {e:?}")))?;
    let keyframes: Vec<(Pose2, PreparedScan)> = backend
        .keyframes()
        .iter()
        .zip(backend.poses())
        .filter(|(keyframe, _)| keyframe.has_scan())
        .map(|(keyframe, &pose)| {
            // MAP_RANGE_M is finite and positive and no clearing range is given: cannot fail.
            let scan = PreparedScan::from_beams(&keyframe.beams, MAP_RANGE_M, None);
            (pose, scan.unwrap_or_default())
        })
        .collect();
    grid.rebuild(keyframes.iter().map(|(pose, scan)| (*pose, scan)))
        .map_err(|e| CliError(format!("map: {e:?}")))?;
    // Scans whose pose is a prediction (the match failed) could clear real walls.
    let measured = seen.scans.iter().filter_map(|(index, scan)| {
        let point = trajectory.get(*index).filter(|p| !p.lost)?;
        Some((point.pose.to_f32(), scan))
    });
    grid.see_through(measured, TRANSIENT_MAX_HITS)
        .map_err(|e| CliError(format!("map: {e:?}")))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use plumbline_core::scan::Beam;

    fn scan(stamp_s: f64) -> Scan<360> {
        let mut s = Scan::new(stamp_s);
        for k in 0..360 {
            let angle = (k as f32).to_radians();
            s.push(Beam::new(angle, 2.0)).unwrap();
        }
        s
    }

    #[test]
    fn kept_scans_stay_within_their_budget_and_span_the_whole_log() {
        let one = PreparedScan::from_beams(scan(0.0).beams(), MAP_RANGE_M, None)
            .unwrap()
            .memory_bytes();
        let mut seen = SeenThrough::<360>::within(20 * one);
        for k in 0..2000 {
            let t = k as f64 * 0.25;
            seen.add(&scan(t));
            assert!(
                seen.bytes <= 20 * one,
                "{} bytes after scan {k}",
                seen.bytes
            );
        }
        assert!(seen.scans.len() >= 10, "{} scans kept", seen.scans.len());
        let last = seen.scans.last().unwrap().0;
        assert!(last >= 1900, "the last kept scan is {last} of 2000");
        assert_eq!(seen.scans.first().unwrap().0, 0);
    }
}
