//! The SLAM driver: one call per scan, online or over a log.
//!
//! Tracking ([`crate::tracker`]) runs on the caller's thread and returns at once; keyframes go to
//! the backend ([`crate::backend`]), inline or on a worker thread ([`crate::worker`]). A scan's
//! pose is its keyframe's graph pose composed with the tracked motion from that keyframe, so
//! when a loop closure moves the keyframes every scan moves with them.

use crate::backend::{Backend, BackendStats};
use crate::config::SlamConfig;
use crate::guard::Guarded;
use crate::observed::Observed;
use crate::tracker::{ConfigError, Tracker};
use crate::worker::Worker;
use plumbline_core::geom::Pose2;
use plumbline_core::matching::local_map::MapCell;
use plumbline_core::scan::Scan;

/// A keyframe moving by more than this (m, rad) counts as a jump of the map (see
/// [`Slam::map_jumped`]); smaller corrections are the graph settling.
pub const MAP_JUMP_M: f32 = 0.05;
pub const MAP_JUMP_RAD: f32 = 0.02;

/// Where one scan ended up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPose {
    /// The keyframe the scan is anchored to (`None` before the first usable scan).
    pub keyframe: Option<usize>,
    /// The scan's pose in the frame of that keyframe.
    pub relative: Pose2,
    /// The scan's pose in the map frame as known now (later loop closures may move it).
    pub pose: Pose2,
    pub new_keyframe: bool,
    /// The match failed and the pose is a prediction.
    pub predicted: bool,
    /// What this scan's match against its keyframe observed, in the map frame's axes: the
    /// covariance and the direction it could not see (a corridor's axis). `None` when nothing
    /// was matched (the first scan, a predicted one).
    pub observed: Option<Observed>,
}

/// Counts of the scan path for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrackingStats {
    pub scans: usize,
    pub predicted_scans: usize,
    /// Runs of predicted scans in a row: each is an interval in which tracking was lost and
    /// the poses are the motion model's, not measurements.
    pub lost_intervals: usize,
    /// Motion guesses that fit badly and were replaced by a wide search, or could not be.
    pub guess_searches_used: usize,
    pub guess_searches_failed: usize,
    /// Of the searches used, those whose pose the local map then contradicted
    /// ([`crate::tracker::Tracked::unconfirmed`]): likely a wrong relocalization.
    pub guess_searches_unconfirmed: usize,
}

/// Where the backend runs.
enum BackendRun<const N: usize> {
    Inline(Box<Backend<N>>),
    Threaded(Worker<N>),
}

pub struct Slam<'m, const N: usize> {
    tracker: Tracker<'m, N>,
    backend: BackendRun<N>,
    /// Tracker-frame poses of all keyframes, to place scans whose keyframe the backend has not
    /// published yet.
    keyframe_tracking: Vec<Pose2>,
    stats: TrackingStats,
    /// The last scan was predicted (tracking is lost).
    lost: bool,
}

/// What a finished run leaves: the backend with its graph and keyframes, and the counts.
pub struct Finished<const N: usize> {
    pub backend: Backend<N>,
    pub tracking: TrackingStats,
}

impl<'m, const N: usize> Slam<'m, N> {
    /// `threaded`: run the backend on a worker thread (the online default), or inline (every
    /// call finishes the keyframe's loop search; for tests and single-core boards).
    pub fn new(
        config: SlamConfig,
        cells: &'m mut [MapCell],
        threaded: bool,
    ) -> Result<Self, ConfigError> {
        let backend = if threaded {
            BackendRun::Threaded(
                Worker::spawn(config)
                    .map_err(|e| ConfigError(format!("cannot start the SLAM worker: {e}")))?,
            )
        } else {
            BackendRun::Inline(Box::new(Backend::new(config)))
        };
        Ok(Self {
            tracker: Tracker::new(config, cells)?,
            backend,
            keyframe_tracking: Vec::new(),
            stats: TrackingStats::default(),
            lost: false,
        })
    }

    /// The last revolution given to [`Self::add_scan`] (`raw`) as the tracker matched it, with
    /// the motion during it removed when it was.
    pub fn matched_scan<'a>(&'a self, raw: &'a Scan<N>) -> &'a Scan<N> {
        self.tracker.matched(raw)
    }

    pub fn tracking_stats(&self) -> TrackingStats {
        self.stats
    }

    /// Feeds the next revolution; `prior` is the motion since the previous scan from another
    /// source (wheel odometry), if any.
    pub fn add_scan(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> ScanPose {
        let tracked = self.tracker.track(scan, prior);
        self.stats.scans += 1;
        self.stats.predicted_scans += tracked.predicted as usize;
        self.stats.lost_intervals += (tracked.predicted && !self.lost) as usize;
        self.lost = tracked.predicted;
        self.stats.guess_searches_unconfirmed += tracked.unconfirmed as usize;
        match tracked.guess {
            Guarded::Searched { .. } | Guarded::SearchedMap { .. } => {
                self.stats.guess_searches_used += 1
            }
            Guarded::NothingBetter => self.stats.guess_searches_failed += 1,
            Guarded::GuessKept => {}
        }
        let new_keyframe = tracked.keyframe.is_some();
        if let Some(keyframe) = tracked.keyframe {
            self.keyframe_tracking.push(keyframe.tracking_pose);
            match &mut self.backend {
                BackendRun::Inline(b) => b.add_keyframe(keyframe),
                BackendRun::Threaded(w) => {
                    w.send(keyframe);
                }
            }
        }
        let Some(anchor) = self.keyframe_tracking.len().checked_sub(1) else {
            return ScanPose {
                keyframe: None,
                relative: Pose2::IDENTITY,
                pose: tracked.pose,
                new_keyframe,
                predicted: tracked.predicted,
                observed: tracked.observed,
            };
        };
        let tracking = self.keyframe_tracking[anchor];
        let relative = tracking.between(tracked.pose);
        let map = self.current_pose(anchor);
        // The map frame is the tracker's turned by what the backend did to the anchor.
        let turn = map.theta - tracking.theta;
        ScanPose {
            keyframe: Some(anchor),
            relative,
            pose: map.compose(relative),
            new_keyframe,
            predicted: tracked.predicted,
            observed: tracked.observed.map(|o| o.rotated(turn)),
        }
    }

    /// The map-frame pose of keyframe `k` as known now: the backend's, or, if it has not got
    /// that far, the newest it has published carried forward by the tracked motion.
    fn current_pose(&self, k: usize) -> Pose2 {
        let worker = match &self.backend {
            BackendRun::Inline(b) => return b.poses()[k],
            BackendRun::Threaded(w) => w,
        };
        match worker.pose_or_latest(k) {
            Some(Ok(pose)) => pose,
            Some(Err((l, pose))) => {
                pose.compose(self.keyframe_tracking[l].between(self.keyframe_tracking[k]))
            }
            None => self.keyframe_tracking[k],
        }
    }

    /// Whether the map moved under `earlier` (a scan this SLAM placed before) by more than
    /// [`MAP_JUMP_M`] or [`MAP_JUMP_RAD`]: a loop closure moves old keyframes, and every later
    /// pose jumps with them, which a consumer of the poses must be told (MAVLink ODOMETRY's
    /// `reset_counter`). `false` when the scan had no keyframe.
    pub fn map_jumped(&self, earlier: &ScanPose) -> bool {
        let Some(now) = earlier.keyframe.and_then(|k| self.keyframe_pose(k)) else {
            return false;
        };
        let then = earlier.pose.compose(earlier.relative.inverse());
        let (d, a) = then.distance_to(now);
        d > MAP_JUMP_M || a > MAP_JUMP_RAD
    }

    /// Keyframes made so far (the threaded backend may not have processed the newest yet).
    pub fn keyframe_count(&self) -> usize {
        self.keyframe_tracking.len()
    }

    /// The map-frame pose of keyframe `k` as known now (see [`Self::add_scan`]); `None` if
    /// there is no such keyframe. A live map places keyframes with it.
    pub fn keyframe_pose(&self, k: usize) -> Option<Pose2> {
        (k < self.keyframe_tracking.len()).then(|| self.current_pose(k))
    }

    /// Whether keyframe `k` keeps its scan in the map (`false`: the backend dropped it as a
    /// repeat of an older keyframe at nearly the same pose); `None` while the backend has not
    /// processed it or there is no such keyframe.
    pub fn keyframe_kept(&self, k: usize) -> Option<bool> {
        match &self.backend {
            BackendRun::Inline(b) => b.keyframes().get(k).map(|kf| kf.has_scan()),
            BackendRun::Threaded(w) => w.kept(k),
        }
    }

    /// Backend counts so far (inline: exact; threaded: as last published).
    pub fn backend_stats(&self) -> BackendStats {
        match &self.backend {
            BackendRun::Inline(b) => b.stats(),
            BackendRun::Threaded(w) => w.stats(),
        }
    }

    /// Waits for the backend to finish every keyframe; `None` if its thread died.
    pub fn finish(self) -> Option<Finished<N>> {
        let backend = match self.backend {
            BackendRun::Inline(mut b) => {
                b.finish();
                *b
            }
            BackendRun::Threaded(w) => w.finish()?,
        };
        Some(Finished {
            backend,
            tracking: self.stats,
        })
    }
}
