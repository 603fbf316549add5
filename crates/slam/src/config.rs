//! Every tunable of the SLAM front end in one place, with units and the reason for each default.

use crate::correlative::{CorrelativeConfig, Rival};
use plumbline_core::matching::local_map::{LineMapConfig, RefineConfig};
use plumbline_core::matching::{MatchConfig, OdometryConfig};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlamConfig {
    /// Scan-to-keyframe tracking (keyframe spacing, matcher). A poorly conditioned match (a
    /// corridor, conditioning below 0.1) takes its keyframe early when the next scan would lie
    /// more than 0.4 m from it: Intel thinned to every 4th scan 0.074 -> 0.029 m (a match
    /// 0.45 m from its keyframe had slid 0.37 m back along a corridor), every 8th 0.033 ->
    /// 0.028 m, Intel 0.0180 -> 0.0178 m, MIT 0.0271 m unchanged with 4 % more keyframes.
    /// Without the conditioning gate MIT, whose scans are 0.21 m apart, took 40 % more
    /// keyframes and ran 28 % slower for 0.0273 m.
    pub odometry: OdometryConfig,
    /// The rolling local map every keyframe is aligned with before it enters the graph.
    pub local_map: LineMapConfig,
    /// The keyframe's alignment with the local map. The scan matcher's pose weighs ten times
    /// what it does in plain odometry: here the pose graph takes the drift out, so the local
    /// map only has to hold heading between loops, and the matcher's near motion is kept
    /// (0.05-1 gave Intel 0.018-0.019 m and MIT 0.030-0.032 m; at 5 the map no longer holds
    /// Intel's heading and loops stop closing).
    pub refine: RefineConfig,
    /// Width of the rolling local map, m (the map is `(size / cell)²` cells of 64 B).
    pub local_map_size_m: f32,
    /// Keyframes per submap: a submap is frozen when it holds this many, and loop closures are
    /// searched only against frozen submaps that are not the newest ones.
    pub keyframes_per_submap: usize,
    pub loops: LoopConfig,
    /// Each keyframe is also matched directly against the one this many before it, and a
    /// good match enters the graph as a second odometry edge (0 or 1: none). Two gave Intel
    /// 0.0182 -> 0.0180 m, MIT 0.0276 -> 0.0271 m, Intel thinned to every 4th scan 0.082 ->
    /// 0.074 m, MIT every 4th 0.044 -> 0.037 m, for one more match per keyframe.
    pub skip_edge_span: usize,
    /// A keyframe tied by a verified loop to an older one closer than this (m, rad) drops its
    /// scan: it adds nothing to the map that the older one does not have.
    pub thin_distance_m: f32,
    pub thin_angle_rad: f32,
    /// Accepted loops wait for this many keyframes before the graph is optimised (bounded
    /// work: one optimisation of the whole graph costs milliseconds); the end of a run
    /// optimises what is left.
    pub optimise_every_keyframes: usize,
    pub guard: GuardConfig,
    pub noise: EdgeNoise,
    /// Remove the motion during each revolution whose beams carry their times
    /// ([`crate::deskew`]) before it is matched and kept. Off by default: a caller whose
    /// lidar spins slowly against the motion (the XV-11) switches it on.
    pub deskew: bool,
}

impl Default for SlamConfig {
    fn default() -> Self {
        Self {
            odometry: OdometryConfig {
                matcher: MatchConfig {
                    recovery_translation_m: 0.45,
                    ..MatchConfig::default()
                },
                keyframe_reach_below_conditioning: 0.1,
                keyframe_reach_m: 0.4,
                ..OdometryConfig::default()
            },
            local_map: LineMapConfig::default(),
            refine: RefineConfig {
                matcher_weight: 0.2,
                ..RefineConfig::default()
            },
            local_map_size_m: 64.0,
            keyframes_per_submap: 20,
            loops: LoopConfig::default(),
            skip_edge_span: 2,
            thin_distance_m: 0.3,
            thin_angle_rad: 0.25,
            optimise_every_keyframes: 10,
            guard: GuardConfig::default(),
            noise: EdgeNoise::default(),
            deskew: false,
        }
    }
}

impl SlamConfig {
    /// SLAM on board a flying vehicle. Its scans come a revolution apart at walking speed
    /// (0.125 m at 4 Hz and 0.5 m/s), so the corridor keyframe rule, made for scans far apart,
    /// has nothing to prevent. It still changed nearly every simulated exploration flight, and
    /// over 100 office frontier flights the flights with a contact rose from 3 to 12-15, so a
    /// flight does without it. Its tracker rests the matcher's recovery search as the
    /// onboard odometry does ([`OdometryConfig::in_flight`]): over Intel frontier seeds 1-100
    /// the odometry's rest alone took 13 % off the CPU and both rests 15 %, every count within
    /// its spread either way.
    pub fn in_flight() -> Self {
        let mut config = Self::default();
        config.odometry.keyframe_reach_below_conditioning = 0.0;
        config.odometry.keyframe_reach_m = f32::INFINITY;
        config.odometry.matcher.recovery_rest_matches =
            OdometryConfig::in_flight().matcher.recovery_rest_matches;
        config
    }
}

/// How loop closures are proposed and checked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopConfig {
    /// Candidates are keyframes whose estimated position lies within this distance of the new
    /// keyframe's, m, plus the drift the odometry may have gathered since (below).
    pub search_radius_m: f32,
    /// Drift allowance per metre travelled since the candidate, m/m.
    pub drift_per_m: f32,
    /// A keyframe verifies one candidate (the nearest first) per `candidate_interval_s` of log
    /// since the previous keyframe, at least one and at most `max_candidates`: the loop
    /// search's work is bounded per second of flight rather than per keyframe, so a vehicle
    /// whose keyframes come sparsely (a slower lidar, a log thinned to every 4th scan) searches
    /// as often per second as one whose keyframes come densely. MIT's keyframes come every
    /// 0.35 s and keep one candidate each; Intel thinned to every 4th scan (a keyframe every
    /// 1.4 s) gets two: 0.113 -> 0.082 m, at Intel 0.0182 m and MIT 0.0276 m unchanged.
    pub max_candidates: usize,
    pub candidate_interval_s: f32,
    /// Submaps younger than this (counting the current one) are not searched: the local map
    /// already ties the keyframe to them.
    pub min_submap_gap: usize,
    /// The candidate's neighbours on each side that join it in the reference of the search
    /// (a 180° scan alone may see too little of a place seen from elsewhere)…
    pub reference_neighbours: usize,
    /// …and on each side when the new keyframe faces more than a right angle away from the
    /// candidate: it sees what the old path saw on its way to and from there, not what the
    /// candidate saw (with two candidates a keyframe, 6 against 2 gave MIT 0.0273 against
    /// 0.0279 m, Intel 0.0180 against 0.0177 m).
    pub reference_neighbours_opposite: usize,
    /// Coarse search before the ICL check: the window around the graph's guess is the drift
    /// the tracker may have gathered since the candidate (a floor plus a share of the distance
    /// travelled, m and rad), at most the maximum; a pose needs at least `min_score` mean
    /// likelihood to be considered.
    pub correlative: CorrelativeConfig,
    pub window_floor_m: f32,
    pub window_max_m: f32,
    pub window_floor_rad: f32,
    pub window_rad_per_m: f32,
    pub window_max_rad: f32,
    pub min_score: f32,
    /// A rival pose away from the best that scores almost as well makes the candidate
    /// ambiguous: a row of alike rooms or doors fits the scan in two places.
    pub rival: Rival,
    /// Verification: the match must pair at least this fraction of the keyframe's points…
    pub min_inlier_ratio: f32,
    /// …with an RMS point-to-line residual at most this, m…
    pub max_rms_m: f32,
    /// …constrain both directions of translation at least this evenly (least over most
    /// information; the matcher reports a corridor's axis below its own, smaller ratio)…
    pub min_conditioning: f32,
    /// …and move the coarse search's answer at most this far, m and rad (further means the
    /// matcher slid into another basin).
    pub max_correction_m: f32,
    pub max_correction_rad: f32,
    /// Matcher used for verification: ICL with its heading/pose recovery search.
    pub matcher: MatchConfig,
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            search_radius_m: 1.5,
            drift_per_m: 0.05,
            max_candidates: 2,
            candidate_interval_s: 0.7,
            min_submap_gap: 2,
            min_inlier_ratio: 0.5,
            max_rms_m: 0.05,
            min_conditioning: 0.1,
            max_correction_m: 0.2,
            max_correction_rad: 0.1,
            reference_neighbours: 2,
            reference_neighbours_opposite: 6,
            correlative: CorrelativeConfig::default(),
            window_floor_m: 0.3,
            window_max_m: 1.5,
            window_floor_rad: 0.05,
            window_rad_per_m: 0.005,
            window_max_rad: 0.35,
            min_score: 0.3,
            rival: Rival {
                exclude_m: 0.5,
                exclude_rad: 0.2,
                ratio: 0.9,
            },
            // The coarse search has already found the basin; the matcher's own recovery
            // would only search again.
            matcher: MatchConfig {
                recovery: false,
                ..MatchConfig::default()
            },
        }
    }
}

/// The check of the tracker's motion guess ([`crate::guard`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuardConfig {
    pub enabled: bool,
    pub correlative: CorrelativeConfig,
    /// A guess whose points' mean likelihood against the keyframe is at least this is kept.
    pub min_guess_score: f32,
    /// Otherwise a window is searched around it: at least this wide, m and rad…
    pub window_m: f32,
    pub window_rad: f32,
    /// …and at most `max_step_m` (the largest move between two scans it can find; full
    /// heading is always allowed), widened to three times the spread below.
    pub max_step_m: f32,
    /// How far the motion may stray from the last one repeated: a floor plus half this
    /// acceleration times the square of the time since the last matched scan, m/s² and rad/s².
    /// Over a long gap the repeated motion says little, so the window grows and the penalty
    /// for leaving the guess fades.
    pub sigma_floor_m: f32,
    pub accel_m_s2: f32,
    pub sigma_floor_rad: f32,
    pub turn_accel_rad_s2: f32,
    /// Score lost by a pose one spread away from the guess (the penalty is quadratic): along
    /// a corridor a 180° lidar sees the same walls wherever it stands, or looking back the way
    /// it came, and only the motion tells those poses apart.
    pub prior_weight: f32,
    /// A pose found replaces the guess if it scores at least this…
    pub min_found_score: f32,
    /// …and this many times the guess's score (the scores are the fit's own, unpenalised).
    pub min_gain: f32,
    /// When the current keyframe holds no pose that fits, the search is made again against
    /// this many last keyframes together (1: not made). On MIT CSAIL thinned to every 8th scan
    /// (turns up to 170° between scans) the keyframe alone found nothing 4-9 times a run and
    /// the match then went astray; with the last 20 none failed. Full rate never gets here.
    pub map_keyframes: usize,
    /// A 180° lidar that turned most of a half turn shares a sliver of its view with the
    /// keyframe, and poses far apart fit that sliver about equally well; the last keyframes
    /// together have seen the rest of the place. So the search is also made against them, and
    /// their answer replaces the keyframe's winner when it is a rival of that winner on the
    /// keyframe (`map_rival`: another peak, fitting the keyframe at least `ratio` of the
    /// winner's score) and the last keyframes fit it better than they fit the winner by
    /// `map_margin` (mean likelihood). The keyframe carries no drift and the last keyframes
    /// together do (along a corridor), so they only choose between the keyframe's own peaks,
    /// never move a peak, and only by a margin drift does not make.
    pub map_rival: Rival,
    pub map_margin: f32,
}

impl Default for GuardConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            correlative: CorrelativeConfig::default(),
            min_guess_score: 0.3,
            window_m: 1.0,
            window_rad: 0.5,
            max_step_m: 2.5,
            sigma_floor_m: 0.1,
            accel_m_s2: 1.0,
            sigma_floor_rad: 0.1,
            turn_accel_rad_s2: 2.0,
            prior_weight: 0.02,
            min_found_score: 0.35,
            min_gain: 1.5,
            map_keyframes: 20,
            map_rival: Rival {
                exclude_m: 0.5,
                exclude_rad: 0.3,
                ratio: 0.8,
            },
            map_margin: 0.25,
        }
    }
}

/// Standard deviations behind the information of graph edges. The matcher's own covariance
/// assumes independent point errors and is about a hundred times too confident (the local map's
/// `matcher_weight` documents the same), so edges use a simple motion model instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeNoise {
    /// Odometry edge: a floor plus a share of the distance travelled, m and m/m.
    pub odometry_m: f32,
    pub odometry_per_m: f32,
    /// Odometry edge heading: a floor plus a share of the turn, rad and rad/rad.
    pub odometry_rad: f32,
    pub odometry_per_rad: f32,
    /// Loop edge, m and rad.
    pub loop_m: f32,
    pub loop_rad: f32,
}

impl Default for EdgeNoise {
    fn default() -> Self {
        Self {
            odometry_m: 0.01,
            odometry_per_m: 0.03,
            odometry_rad: 0.004,
            odometry_per_rad: 0.03,
            loop_m: 0.03,
            loop_rad: 0.01,
        }
    }
}
