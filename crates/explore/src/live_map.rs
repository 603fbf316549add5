//! The occupancy grid on board, kept current from the online SLAM.
//!
//! Each keyframe's scan is inserted once the backend has decided whether it keeps it (a
//! keyframe that only repeats an older one is dropped from the map, as the slam command's map
//! drops it), at the keyframe's pose as known then. When the pose graph is optimised, loop
//! closure has moved the keyframes, and the grid is rebuilt from every kept keyframe at its new
//! pose. Between optimisations a scan costs at most the insertion of the keyframes that became
//! ready; the grid is then the one `plumbline slam --map` would draw from the same keyframes.

use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_slam::grid::{GridConfig, GridError, OccupancyGrid, PreparedScan};
use plumbline_slam::{ScanPose, Slam};

/// What one update did, for cost accounting.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MapUpdate {
    /// Keyframes inserted at their current pose.
    pub inserted: usize,
    /// The whole grid was rebuilt after an optimisation.
    pub rebuilt: bool,
}

pub struct LiveMap {
    grid: OccupancyGrid,
    map_range_m: f32,
    /// Keyframe `k`'s scan (`None` once the backend dropped it, or before it was seen).
    scans: Vec<Option<PreparedScan>>,
    /// Keyframes before this one are settled: inserted or dropped.
    settled: usize,
    /// The backend's optimisation count the grid's poses are from.
    optimisations: usize,
    /// Changes whenever the grid does (inserts and rebuilds), so planners can tell.
    version: u64,
    rebuilds: usize,
}

impl LiveMap {
    pub fn new(grid: GridConfig, map_range_m: f32) -> Result<Self, GridError> {
        if !(map_range_m.is_finite() && map_range_m > 0.0) {
            return Err(GridError::Config(format!(
                "map range {map_range_m} m must be finite and positive"
            )));
        }
        Ok(Self {
            grid: OccupancyGrid::new(grid)?,
            map_range_m,
            scans: Vec::new(),
            settled: 0,
            optimisations: 0,
            version: 0,
            rebuilds: 0,
        })
    }

    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// Changes whenever the grid changes.
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Rebuilds so far (one per optimisation seen).
    pub fn rebuilds(&self) -> usize {
        self.rebuilds
    }

    /// Takes in the scan `slam` has just placed (`at`, from [`Slam::add_scan`]): keeps its
    /// beams if it made a keyframe, inserts every keyframe the backend has settled since the
    /// last call, and rebuilds when the graph was optimised. A scan the grid refuses (a pose
    /// beyond the map's extent) is reported and left out; the map stays as it was.
    pub fn update<const N: usize>(
        &mut self,
        slam: &Slam<'_, N>,
        scan: &Scan<N>,
        at: &ScanPose,
    ) -> Result<MapUpdate, GridError> {
        if let (true, Some(k)) = (at.new_keyframe, at.keyframe) {
            if self.scans.len() <= k {
                self.scans.resize(k + 1, None);
            }
            let prepared = PreparedScan::from_beams(
                scan.beams(),
                self.map_range_m,
                self.grid.config().no_return_clear_m,
            )?;
            self.scans[k] = Some(prepared);
        }
        let mut update = MapUpdate::default();
        let optimisations = slam.backend_stats().optimisations;
        let mut first_error = None;
        if optimisations != self.optimisations {
            self.optimisations = optimisations;
            update.rebuilt = true;
            self.rebuilds += 1;
            self.grid.clear();
            for k in 0..self.settled {
                if let Err(e) = self.insert(slam, k) {
                    first_error.get_or_insert(e);
                }
            }
        }
        while self.settled < self.scans.len() {
            let k = self.settled;
            match slam.keyframe_kept(k) {
                None => break,
                Some(false) => self.scans[k] = None,
                Some(true) => {
                    update.inserted += 1;
                    if let Err(e) = self.insert(slam, k) {
                        first_error.get_or_insert(e);
                    }
                }
            }
            self.settled += 1;
        }
        if update.rebuilt || update.inserted > 0 {
            self.version += 1;
        }
        first_error.map_or(Ok(update), Err)
    }

    fn insert<const N: usize>(&mut self, slam: &Slam<'_, N>, k: usize) -> Result<(), GridError> {
        let (Some(scan), Some(pose)) = (&self.scans[k], slam.keyframe_pose(k)) else {
            return Ok(());
        };
        self.grid
            .insert(pose, scan)
            .map_err(|e| GridError::InKeyframe {
                index: k,
                error: Box::new(e),
            })
    }

    /// Inserts a scan at a known pose without SLAM (synthetic maps, replays of a finished run).
    pub fn insert_at(&mut self, pose: Pose2, scan: &PreparedScan) -> Result<(), GridError> {
        self.grid.insert(pose, scan)?;
        self.version += 1;
        Ok(())
    }
}
