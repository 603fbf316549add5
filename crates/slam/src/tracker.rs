//! The scan path: every scan matched to the current keyframe, every keyframe aligned with the
//! rolling local map, and the motion guess checked before each match ([`crate::guard`]).
//! It owns no global state, so its cost per scan stays flat however large the map grows.

use crate::config::SlamConfig;
use crate::deskew::{deskew, is_timed, rate_of, MotionHistory};
use crate::guard::{Guarded, GuessGuard};
use crate::keyframe::Keyframe;
use crate::observed::Observed;
use plumbline_core::geom::Pose2;
use plumbline_core::matching::local_map::{
    LineMap, MapCell, MapUse, MappedOdometry, RefineRefusal,
};
use plumbline_core::matching::OdometryStep;
use plumbline_core::scan::sweep::SweepMotion;
use plumbline_core::scan::Scan;

/// What tracking made of one scan.
#[derive(Clone, Debug)]
pub struct Tracked {
    /// Pose in the tracker's own (drifting) frame.
    pub pose: Pose2,
    /// The scan became a keyframe.
    pub keyframe: Option<Keyframe>,
    /// The match failed: the pose is a prediction.
    pub predicted: bool,
    /// What the scan's match observed, in the tracker frame's axes; `None` when nothing was
    /// matched (the first scan, a prediction).
    pub observed: Option<Observed>,
    pub guess: Guarded,
    /// The guess came from a wide search, and the local map refused the keyframe the match
    /// made from it as a correction it cannot have drifted by: the search and the map
    /// disagree about where the vehicle is, and the pose may be wrong.
    pub unconfirmed: bool,
}

/// The local map could not be made from the configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError(pub String);

/// Cells the rolling local map needs for `config` (the caller owns them, as in the onboard code).
pub fn local_map_cells(config: &SlamConfig) -> Vec<MapCell> {
    let side = (config.local_map_size_m / config.local_map.cell_m)
        .ceil()
        .max(1.0) as usize;
    vec![MapCell::default(); side * side]
}

pub struct Tracker<'m, const N: usize> {
    config: SlamConfig,
    odometry: Box<MappedOdometry<'m, N>>,
    guard: GuessGuard,
    /// The current keyframe (the guard checks guesses against it) and how many came before.
    keyframe: Option<Keyframe>,
    keyframes: usize,
    path_m: f32,
    /// The last pose and the motion that led to it (the lidar-only guess).
    last_pose: Pose2,
    last_motion: Pose2,
    /// When the last scan that matched was taken, s.
    last_matched_s: f64,
    /// The last scans' poses: the rate a revolution is de-skewed with.
    history: MotionHistory,
    /// The current scan with the motion during its revolution removed (when its beams carry
    /// their times): what is matched and kept in keyframes. `last_deskewed`: the last scan
    /// tracked is the one in it.
    deskewed: Option<Box<Scan<N>>>,
    last_deskewed: bool,
}

impl<'m, const N: usize> Tracker<'m, N> {
    pub fn new(config: SlamConfig, cells: &'m mut [MapCell]) -> Result<Self, ConfigError> {
        let map = LineMap::new(cells, config.local_map)
            .map_err(|e| ConfigError(format!("local map: {e:?}")))?;
        Ok(Self {
            config,
            odometry: Box::new(MappedOdometry::new(
                config.odometry,
                map,
                config.refine,
                None,
            )),
            guard: GuessGuard::new(config.guard),
            keyframe: None,
            keyframes: 0,
            path_m: 0.0,
            last_pose: Pose2::IDENTITY,
            last_motion: Pose2::IDENTITY,
            last_matched_s: f64::NAN,
            history: MotionHistory::default(),
            deskewed: None,
            last_deskewed: false,
        })
    }

    /// Tracks the next revolution; `prior` is the motion since the previous scan from another
    /// source (wheel odometry), if any.
    pub fn track(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> Tracked {
        let mut deskewed = self.deskewed.take().unwrap_or_default();
        let motion = self.sweep_motion(scan, prior);
        self.last_deskewed = motion.is_some();
        let tracked = match motion {
            Some(motion) => {
                deskew(scan, motion, &mut deskewed);
                self.track_deskewed(&deskewed, prior)
            }
            None => self.track_deskewed(scan, prior),
        };
        self.deskewed = Some(deskewed);
        self.history.push(scan.stamp_s, tracked.pose);
        tracked
    }

    /// The last revolution as it was matched: `raw` (that revolution as given) with the motion
    /// during it removed when the tracker removed it.
    pub fn matched<'a>(&'a self, raw: &'a Scan<N>) -> &'a Scan<N> {
        match &self.deskewed {
            Some(deskewed) if self.last_deskewed => deskewed,
            _ => raw,
        }
    }

    /// How the vehicle moves during `scan`'s revolution: at the caller's prior's rate, or the
    /// recent scans' ([`MotionHistory`]); `None` when its beams carry no times or no rate is
    /// known yet.
    fn sweep_motion(&self, scan: &Scan<N>, prior: Option<Pose2>) -> Option<SweepMotion> {
        if !(self.config.deskew && is_timed(scan)) {
            return None;
        }
        match (
            prior.filter(|p| p.is_finite()),
            self.history.newest_stamp_s(),
        ) {
            (Some(prior), Some(last_s)) => rate_of(prior, (scan.stamp_s - last_s) as f32),
            _ => self.history.rate(),
        }
    }

    /// Tracks a revolution whose motion has been removed (or needed no removing).
    fn track_deskewed(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> Tracked {
        let (guess, prior) = self.guarded_prior(scan, prior);
        // The match is made in the axes of the keyframe it is made against.
        let reference_heading = self.keyframe.as_ref().map(|k| k.tracking_pose.theta);
        let step = self.odometry.update(scan, prior);
        let observed = match (step.step, reference_heading) {
            (OdometryStep::Matched { result, .. }, Some(heading)) => {
                Some(Observed::from_match(&result).rotated(heading))
            }
            _ => None,
        };
        let pose = self.odometry.pose();
        if matches!(
            step.step,
            OdometryStep::Matched { .. } | OdometryStep::Started
        ) {
            self.last_matched_s = scan.stamp_s;
        }
        let searched = matches!(
            guess,
            Guarded::Searched { .. } | Guarded::SearchedMap { .. }
        );
        let contradicted = matches!(
            step.map,
            MapUse::Refused(RefineRefusal::Diverged | RefineRefusal::Implausible { .. })
        );
        let unconfirmed = searched && contradicted;
        self.last_motion = self.last_pose.between(pose);
        self.last_pose = pose;
        let keyframe = (!matches!(step.map, MapUse::NotKeyframe)).then(|| {
            if let Some(previous) = &self.keyframe {
                self.path_m += previous.tracking_pose.between(pose).translation().norm();
            }
            let submap = self.keyframes / self.config.keyframes_per_submap.max(1);
            let predicted = matches!(step.map, MapUse::Skipped) || unconfirmed;
            let kf = Keyframe::new(scan, pose, submap, self.path_m, predicted);
            self.keyframe = Some(kf.clone());
            self.keyframes += 1;
            kf
        });
        Tracked {
            pose,
            keyframe,
            predicted: matches!(step.step, OdometryStep::Predicted { .. }),
            observed,
            guess,
            unconfirmed,
        }
    }

    /// The current keyframe's index and its pose in the tracker's frame.
    pub fn keyframe(&self) -> Option<(usize, &Keyframe)> {
        self.keyframe.as_ref().map(|k| (self.keyframes - 1, k))
    }

    /// The motion prior for the tracker: the caller's, unless the guess it leads to fits the
    /// keyframe badly and a wide search finds a better one.
    fn guarded_prior(&mut self, scan: &Scan<N>, prior: Option<Pose2>) -> (Guarded, Option<Pose2>) {
        let Some(keyframe) = &self.keyframe else {
            return (Guarded::GuessKept, prior);
        };
        let motion = prior.filter(|p| p.is_finite()).unwrap_or(self.last_motion);
        let guess = keyframe
            .tracking_pose
            .between(self.last_pose.compose(motion));
        let points: Vec<_> = scan
            .beams()
            .iter()
            .filter(|b| b.valid)
            .map(|b| b.point())
            .collect();
        let gap_s = (scan.stamp_s - self.last_matched_s) as f32;
        match self
            .guard
            .check(keyframe, self.keyframes, &points, guess, gap_s)
        {
            (checked @ (Guarded::Searched { .. } | Guarded::SearchedMap { .. }), Some(found)) => (
                checked,
                Some(
                    self.last_pose
                        .between(keyframe.tracking_pose.compose(found)),
                ),
            ),
            (checked, _) => (checked, prior),
        }
    }
}
