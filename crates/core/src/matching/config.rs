//! Matcher configuration: one struct, documented defaults, SI units.

/// Which matcher runs (chosen by configuration so every variant sees the same input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatcherKind {
    /// Seed 000 Fig. 4 as written: translation-only gradient descent, fixed iterations,
    /// the two closest previous points found by brute force. Kept for comparison.
    IclPaper,
    /// Plumbline's ICL: point-to-line Gauss-Newton in SE(2) with windowed correspondences,
    /// seed 000 sec. 4.2 rejection, a robust weight, covariance and degeneracy report.
    Icl,
    /// Point-to-point ICP with the closed-form 2-D rotation (the GTAR team's choice, seed 002).
    Icp,
    /// Point-to-line ICP solved exactly for fixed correspondences (Censi 2008).
    Plicp,
}

impl MatcherKind {
    pub const ALL: [MatcherKind; 4] = [
        MatcherKind::IclPaper,
        MatcherKind::Icl,
        MatcherKind::Icp,
        MatcherKind::Plicp,
    ];

    pub fn name(self) -> &'static str {
        match self {
            MatcherKind::IclPaper => "icl-paper",
            MatcherKind::Icl => "icl",
            MatcherKind::Icp => "icp",
            MatcherKind::Plicp => "plicp",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchConfig {
    pub kind: MatcherKind,
    /// Association passes at most.
    pub max_iterations: u16,
    /// Valid points needed in each scan, and correspondences needed to solve.
    pub min_points: u16,
    /// Farthest a current point may be from its reference point in the first pass, m.
    pub max_correspondence_m: f32,
    /// Later passes gate at `gate_sigmas` robust standard deviations of the residual, but never
    /// tighter than this, m.
    pub min_gate_m: f32,
    pub gate_sigmas: f32,
    /// Reference points searched either side of the projected bearing.
    pub search_half_window: u16,
    /// Neighbours closer than this share a local line (and PL-ICP segments are no longer), m.
    pub line_neighbour_m: f32,
    /// A local line is fitted to neighbours spanning at least this far each side, m.
    pub line_min_extent_m: f32,
    /// Smallest/largest spread of a local neighbourhood for it to count as a line.
    pub line_max_flatness: f32,
    /// Converged when an update moves less than these.
    pub convergence_m: f32,
    pub convergence_rad: f32,
    /// A translation direction is weak (a corridor's axis) when its point-to-line information
    /// is below this fraction of the best-constrained direction's: the line metric then holds
    /// it at the guess, and `icl` measures it from the wall ends both scans see instead. It is
    /// reported degenerate only when those do not measure it either (a featureless corridor).
    pub degenerate_ratio: f32,
    /// `icl` only: when a translation direction is degenerate, at most this many point-to-point
    /// (`icp`) passes, started from the answer, estimate the motion along it instead of leaving
    /// the guess there; 0 leaves the guess. They give no variance: unless the wall ends then
    /// measure the direction, it is still reported degenerate with its variance unobserved, so
    /// an estimator fusing the match keeps ignoring it.
    pub degenerate_point_passes: u16,
    /// A converged line-metric match whose conditioning (least over most translational
    /// information) is below this has its weakest direction checked for points that face it;
    /// with fewer than `min_facing_points` within `facing_max_angle_rad` of it, the direction is
    /// degenerate after all (held at the guess, then measured as above). 0 (the default) turns
    /// the check off: it is for lidars whose range noise tilts the fitted normals by several
    /// degrees (the XV-11); on the SICK logs small-angle structure is real information.
    pub localizability_check_below: f32,
    /// How far a matched point's line normal may lean from the weak direction and still count
    /// as facing it, rad. Default 60°: a door frame or corner seen obliquely still measures it.
    pub facing_max_angle_rad: f32,
    /// Facing points needed for the weak direction to count as measured. Default 12, set on
    /// the simulated XV-11 surveys.
    pub min_facing_points: u16,
    /// Seed 000 sec. 4.2: a point is dynamic or an outlier when its cost J at the initial guess
    /// exceeds `gain * (dx_prev^2 + dy_prev^2) + floor^2`.
    pub dynamic_rejection: bool,
    pub dynamic_gain: f32,
    pub dynamic_floor_m: f32,
    /// A solution farther than this from the initial guess is reported as diverged.
    pub max_correction_m: f32,
    pub max_correction_rad: f32,
    /// When a match fails, stops at the iteration limit or keeps fewer than
    /// `recovery_below_inlier_ratio` of its points, search
    /// heading within +-`recovery_range_rad` in steps of `recovery_step_rad`, scoring points
    /// within `recovery_radius_m` of a reference point, and match again from the best.
    pub recovery: bool,
    pub recovery_below_inlier_ratio: f32,
    pub recovery_range_rad: f32,
    pub recovery_step_rad: f32,
    pub recovery_radius_m: f32,
    /// If the heading search does not rescue the match, search translation too, +- this much.
    pub recovery_translation_m: f32,
    /// After a search that a low inlier ratio alone started finds nothing better than the
    /// first match, the next this many matches search only on a hard failure (the iteration
    /// limit, too few correspondences, divergence); 0 never rests. In the slowest simulated
    /// Intel flights the first match pairs fewer than half its points on nearly every
    /// revolution: the search then runs on each, beats the first match about once in sixteen
    /// and takes a quarter of the flight part's CPU. Off by default: on the real logs the
    /// skipped searches are rescues (MIT CSAIL odometry ends 1.1 m off instead of 0.064 m).
    pub recovery_rest_matches: u8,
    /// `icl-paper` only: seed 000 sec. 4.2's rejection as written (off by default): a point is
    /// left out when its cost J exceeds `dynamic_gain * (dx_prev^2 + dy_prev^2)
    /// + paper_rejection_floor_m^2`; the paper gives no floor (0).
    pub paper_rejection: bool,
    pub paper_rejection_floor_m: f32,
    /// `icl-paper` only: learning rate times point count, and its fixed iteration count.
    pub paper_rate_per_point: f32,
    pub paper_iterations: u16,
}

impl Default for MatchConfig {
    fn default() -> Self {
        Self {
            kind: MatcherKind::Icl,
            max_iterations: 30,
            min_points: 20,
            max_correspondence_m: 0.5,
            min_gate_m: 0.05,
            gate_sigmas: 4.0,
            search_half_window: 3,
            line_neighbour_m: 0.3,
            line_min_extent_m: 0.1,
            line_max_flatness: 0.05,
            convergence_m: 1e-3,
            convergence_rad: 5e-4,
            degenerate_ratio: 0.02,
            degenerate_point_passes: 5,
            localizability_check_below: 0.0,
            facing_max_angle_rad: core::f32::consts::FRAC_PI_3,
            min_facing_points: 12,
            dynamic_rejection: true,
            dynamic_gain: 4.0,
            dynamic_floor_m: 0.2,
            max_correction_m: 1.5,
            max_correction_rad: 0.8,
            recovery: true,
            recovery_below_inlier_ratio: 0.5,
            recovery_range_rad: 0.9,
            recovery_step_rad: 0.035,
            recovery_radius_m: 0.15,
            recovery_translation_m: 1.2,
            recovery_rest_matches: 0,
            paper_rejection: false,
            paper_rejection_floor_m: 0.0,
            paper_rate_per_point: 1.0,
            paper_iterations: 20,
        }
    }
}

impl MatchConfig {
    pub fn with_kind(kind: MatcherKind) -> Self {
        Self {
            kind,
            ..Self::default()
        }
    }
}
