//! The occupancy grid on board, kept current from the online SLAM.
//!
//! Each keyframe's scan is inserted once the backend has decided whether it keeps it (a
//! keyframe that only repeats an older one is dropped from the map, as the slam command's map
//! drops it), at the keyframe's pose as known then. When the pose graph is optimised, loop
//! closure has moved the keyframes, and the grid is rebuilt from every kept keyframe at its new
//! pose. Between optimisations a scan costs at most the insertion of the keyframes that became
//! ready; the grid is then the one `plumbline slam --map` would draw from the same keyframes.
//!
//! A rebuild costs the whole map, tens of milliseconds in a building, so it is spread over
//! the scans that follow: a second grid is filled a bounded number of keyframes per update
//! while the first keeps serving, and takes its place once it has caught up.
//!
//! An optimisation that moved no keyframe far enough to shift any of its beams' ends by half a
//! cell from where the grid drew them starts no rebuild: the grid already holds what a rebuild
//! would draw, to within the half cell its own quantisation rounds every end by. Without this,
//! a flight that closes a loop every few keyframes redraws the whole map without pause and,
//! its rebuilds restarted before they finish, serves a map that never catches up.
//!
//! A loop closure mostly bends the loop it closed: the keyframes drawn before the first one it
//! moved stay where they were. A rebuild therefore keeps a copy of its grid as it reaches that
//! keyframe, and the next rebuild starts from the copy when none of the keyframes in it has
//! moved by half a cell since, drawing only the keyframes after it.
//!
//! A rebuild's grid is only read when it is copied or takes the serving grid's place, and a
//! new optimisation throws away the rebuild under way, so the keyframes it takes in are queued
//! with their poses and drawn only when the grid is next read: the same keyframes at the same
//! poses in the same order, with no work spent on a rebuild that never finishes (a keyframe
//! the grid refuses is then reported by the update that draws it).

use plumbline_core::geom::Pose2;
use plumbline_core::scan::Scan;
use plumbline_slam::grid::{GridConfig, GridError, OccupancyGrid, PreparedScan};
use plumbline_slam::{ScanPose, Slam};

/// What one update did, for cost accounting.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MapUpdate {
    /// Keyframes inserted at their current pose.
    pub inserted: usize,
    /// Keyframes inserted into the grid being rebuilt.
    pub rebuilt_keyframes: usize,
    /// A rebuilt grid took the place of the old one.
    pub rebuilt: bool,
}

/// A grid being filled at the poses of the latest optimisation (or a copy of one part way).
#[derive(Clone)]
struct Rebuild {
    grid: OccupancyGrid,
    /// Keyframes before this one are in it, or queued for it.
    next: usize,
    /// The pose each keyframe was drawn at in it.
    drawn: Vec<Option<Pose2>>,
    /// Keyframes taken in but not drawn yet, with the poses to draw them at, in order.
    queued: Vec<(usize, Pose2)>,
}

impl Rebuild {
    /// Draws the queued keyframes, so that the grid holds every keyframe taken in; a keyframe
    /// the grid refuses is left out and the first such refusal returned.
    fn draw_queued(&mut self, scans: &[Option<PreparedScan>]) -> Result<(), GridError> {
        let mut first_error = None;
        for (k, pose) in self.queued.drain(..) {
            if let Some(scan) = &scans[k] {
                if let Err(e) = draw(&mut self.grid, &mut self.drawn, k, pose, scan) {
                    first_error.get_or_insert(e);
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }
}

pub struct LiveMap {
    grid: OccupancyGrid,
    map_range_m: f32,
    /// Keyframe `k`'s scan (`None` once the backend dropped it, or before it was seen).
    scans: Vec<Option<PreparedScan>>,
    /// The farthest beam end of keyframe `k`'s scan from its sensor, m: how far a turn of the
    /// keyframe moves its beams' ends per radian.
    reach_m: Vec<f32>,
    /// The pose keyframe `k` was drawn at in the serving grid (`None` while it is not in it).
    drawn: Vec<Option<Pose2>>,
    /// Keyframes before this one are settled: inserted or dropped.
    settled: usize,
    /// The backend's optimisation count the grid's poses are from.
    optimisations: usize,
    /// Changes whenever the grid does (inserts and rebuilds), so planners can tell.
    version: u64,
    rebuilds: usize,
    rebuilding: Option<Rebuild>,
    /// A copy of a rebuild holding the keyframes before the first one its optimisation moved.
    snapshot: Option<Rebuild>,
    /// The keyframe before which the rebuild under way copies itself into `snapshot`.
    snapshot_at: usize,
    /// Most keyframes a rebuild inserts per update.
    rebuild_per_update: usize,
}

impl LiveMap {
    /// `rebuild_per_update`: most keyframes a rebuild after an optimisation inserts per
    /// update (at least 1).
    pub fn new(
        grid: GridConfig,
        map_range_m: f32,
        rebuild_per_update: usize,
    ) -> Result<Self, GridError> {
        if !(map_range_m.is_finite() && map_range_m > 0.0) {
            return Err(GridError::Config(format!(
                "map range {map_range_m} m must be finite and positive"
            )));
        }
        Ok(Self {
            grid: OccupancyGrid::new(grid)?,
            map_range_m,
            scans: Vec::new(),
            reach_m: Vec::new(),
            drawn: Vec::new(),
            settled: 0,
            optimisations: 0,
            version: 0,
            rebuilds: 0,
            rebuilding: None,
            snapshot: None,
            snapshot_at: 0,
            rebuild_per_update: rebuild_per_update.max(1),
        })
    }

    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// Changes whenever the grid changes.
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Rebuilds completed so far (an optimisation during a rebuild starts it again).
    pub fn rebuilds(&self) -> usize {
        self.rebuilds
    }

    /// Takes in the scan `slam` has just placed (`at`, from [`Slam::add_scan`]): keeps its
    /// beams if it made a keyframe, inserts every keyframe the backend has settled since the
    /// last call, and goes on rebuilding when the graph was optimised. A scan the grid refuses (a pose
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
                self.reach_m.resize(k + 1, 0.0);
                self.drawn.resize(k + 1, None);
            }
            let prepared = PreparedScan::from_beams(
                scan.beams(),
                self.map_range_m,
                self.grid.config().no_return_clear_m,
            )?;
            self.reach_m[k] = prepared
                .hits()
                .iter()
                .chain(prepared.clears())
                .map(|p| p.norm())
                .fold(0.0, f32::max);
            self.scans[k] = Some(prepared);
        }
        let mut update = MapUpdate::default();
        let optimisations = slam.backend_stats().optimisations;
        let mut first_error = None;
        if optimisations != self.optimisations {
            self.optimisations = optimisations;
            let half_cell_m = 0.5 * self.grid.config().resolution_m;
            if let Some(first) = self.first_moved(&self.drawn, slam, half_cell_m) {
                self.start_rebuild(slam, first, half_cell_m)?;
            } else if self.rebuilding.is_some() {
                self.start_rebuild(slam, self.settled, half_cell_m)?;
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
        if let Err(e) = self.rebuild(slam, self.rebuild_per_update, &mut update) {
            first_error.get_or_insert(e);
        }
        if update.rebuilt || update.inserted > 0 {
            self.version += 1;
        }
        first_error.map_or(Ok(update), Err)
    }

    /// Finishes a rebuild in progress at once, or rebuilds now if a keyframe was drawn
    /// anywhere but at its current pose (the end of a flight, or a test that compares the map
    /// with the slam's): the grid is then exactly the one drawn at the final poses.
    pub fn finish_rebuild<const N: usize>(&mut self, slam: &Slam<'_, N>) -> Result<(), GridError> {
        if let (None, Some(first)) = (&self.rebuilding, self.first_moved(&self.drawn, slam, 0.0)) {
            self.start_rebuild(slam, first, 0.0)?;
        }
        let mut update = MapUpdate::default();
        self.rebuild(slam, usize::MAX, &mut update)?;
        if update.rebuilt {
            self.version += 1;
        }
        Ok(())
    }

    /// Inserts up to `budget` settled keyframes into the grid being rebuilt, and puts it in
    /// place once it holds them all.
    fn rebuild<const N: usize>(
        &mut self,
        slam: &Slam<'_, N>,
        budget: usize,
        update: &mut MapUpdate,
    ) -> Result<(), GridError> {
        let mut first_error = None;
        let mut spent = 0;
        while let Some(next) = self.rebuilding.as_ref().map(|r| r.next) {
            if next >= self.settled {
                if let Some(mut done) = self.rebuilding.take() {
                    if let Err(e) = done.draw_queued(&self.scans) {
                        first_error.get_or_insert(e);
                    }
                    self.grid = done.grid;
                    self.drawn = done.drawn;
                    self.drawn.resize(self.scans.len(), None);
                    self.rebuilds += 1;
                    update.rebuilt = true;
                }
                break;
            }
            if spent >= budget {
                break;
            }
            let Some(r) = self.rebuilding.as_mut() else {
                break;
            };
            if next == self.snapshot_at && self.snapshot.as_ref().is_none_or(|s| s.next != next) {
                if let Err(e) = r.draw_queued(&self.scans) {
                    first_error.get_or_insert(e);
                }
                self.snapshot = Some(r.clone());
            }
            if self.scans[next].is_some() {
                spent += 1;
                update.rebuilt_keyframes += 1;
                if let Some(pose) = slam.keyframe_pose(next) {
                    r.queued.push((next, pose));
                }
            }
            r.next += 1;
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Starts a new rebuild in place of any under way: from the snapshot if none of its
    /// keyframes has moved by `tolerance_m`, else from an empty grid. It copies itself into the
    /// snapshot before keyframe `first_moved` (the first the optimisation moved).
    fn start_rebuild<const N: usize>(
        &mut self,
        slam: &Slam<'_, N>,
        first_moved: usize,
        tolerance_m: f32,
    ) -> Result<(), GridError> {
        let from_snapshot = self
            .snapshot
            .as_ref()
            .filter(|s| {
                let drawn = &s.drawn[..s.next.min(s.drawn.len())];
                self.first_moved(drawn, slam, tolerance_m).is_none()
            })
            .cloned();
        self.rebuilding = Some(match from_snapshot {
            Some(snapshot) => snapshot,
            None => Rebuild {
                grid: OccupancyGrid::new(*self.grid.config())?,
                next: 0,
                drawn: vec![None; self.scans.len()],
                queued: Vec::new(),
            },
        });
        self.snapshot_at = first_moved;
        Ok(())
    }

    /// The first keyframe the graph has moved so far from the pose in `drawn` that one of its
    /// beams' ends may lie more than `tolerance_m` away (a shift plus a turn times the farthest
    /// end bounds how far any end moved).
    fn first_moved<const N: usize>(
        &self,
        drawn: &[Option<Pose2>],
        slam: &Slam<'_, N>,
        tolerance_m: f32,
    ) -> Option<usize> {
        (0..self.settled.min(drawn.len())).find(|&k| {
            let (Some(drawn), Some(now)) = (drawn[k], slam.keyframe_pose(k)) else {
                return false;
            };
            if drawn == now {
                return false;
            }
            let (shift_m, turn_rad) = drawn.distance_to(now);
            shift_m + turn_rad * self.reach_m[k] > tolerance_m
        })
    }

    /// Inserts keyframe `k` at its current pose into the serving grid.
    fn insert<const N: usize>(&mut self, slam: &Slam<'_, N>, k: usize) -> Result<(), GridError> {
        let (Some(scan), Some(pose)) = (&self.scans[k], slam.keyframe_pose(k)) else {
            return Ok(());
        };
        draw(&mut self.grid, &mut self.drawn, k, pose, scan)
    }

    /// Inserts a scan at a known pose without SLAM (synthetic maps, replays of a finished run).
    pub fn insert_at(&mut self, pose: Pose2, scan: &PreparedScan) -> Result<(), GridError> {
        self.grid.insert(pose, scan)?;
        self.version += 1;
        Ok(())
    }
}

/// Draws keyframe `k`'s scan into `grid` at `pose`, and notes the pose in `drawn`.
fn draw(
    grid: &mut OccupancyGrid,
    drawn: &mut Vec<Option<Pose2>>,
    k: usize,
    pose: Pose2,
    scan: &PreparedScan,
) -> Result<(), GridError> {
    grid.insert(pose, scan).map_err(|e| GridError::InKeyframe {
        index: k,
        error: Box::new(e),
    })?;
    if drawn.len() <= k {
        drawn.resize(k + 1, None);
    }
    drawn[k] = Some(pose);
    Ok(())
}
