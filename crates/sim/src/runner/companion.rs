//! The companion computer of an exploring vehicle, as it runs in simulation: on every lidar
//! revolution the online SLAM places the scan, the explorer updates its live map and decides
//! where to go (or that exploring is done), and seed 002's velocity field turns that into a
//! velocity setpoint that keeps clear of what the scan sees. The flight part gets the SLAM pose
//! as a pose fix and the setpoint through [`CompanionMessages`], never the SLAM itself.
//!
//! The mission from the companion's side: wait for the autopilot to hold after take-off, ask
//! it to explore, explore until the explorer is done or the time left only covers the way home,
//! then say so and fly the planned path home; the autopilot lands when it is there. A way home
//! that makes no progress is planned again round the place it stalled at, and if it still makes
//! none the companion asks to land in place ([`super::progress`] has the bounds). The SLAM
//! guesses each revolution's motion from the flight part's estimate ([`EstimatedMotion`]).
//! Everything runs inline (the SLAM backend too), so a run is a function of its seed.

use super::fix_covariance::fix_covariance;
use super::landing_spot::landing_spot;
use super::onboard_link::{CompanionComputer, FlightLog};
use super::progress::{ProgressWatch, Verdict};
use plumbline_core::estimate::ekf::EkfConfig;
use plumbline_core::flight::mission::MissionConfig;
use plumbline_core::geom::{normalize_angle, Pose2, Vec2};
use plumbline_core::guidance::config::GuidanceConfig;
use plumbline_core::guidance::step::{Guidance, GuidanceMode};
use plumbline_core::msgs::{
    CompanionMessages, CompanionSetpoint, FlightMode, MissionCommand, PoseFix, SetpointTarget,
};
use plumbline_core::scan::Scan;
use plumbline_explore::{BlindBudget, DoneReason, ExploreStep, Explorer, Path};
use plumbline_slam::{EstimatedMotion, ScanPose, Slam};
use std::cell::RefCell;
use std::rc::Rc;

/// Wall segments one revolution may yield to the guidance.
const WALL_SEGMENTS: usize = 64;
/// The way home is planned again this often while exploring (its length sets when to turn
/// back) and while returning, s.
const HOME_PLAN_EVERY_S: f64 = 2.0;
/// Speed assumed for the way home when deciding when to turn back, m/s (below the guidance's
/// cruise speed: the field slows down near walls and in doors).
const RETURN_SPEED_M_S: f64 = 0.25;
/// Time kept for the final approach, the descent and the unforeseen, s.
const RETURN_RESERVE_S: f64 = 30.0;
/// Within this distance of home the companion sends the home point itself, m.
const HOME_APPROACH_M: f32 = 0.5;
/// Lookahead along the path home, m.
const HOME_LOOKAHEAD_M: f32 = 1.0;
/// Fastest turn the companion asks for, rad/s: the scan matcher on board loses a slow lidar
/// when the heading sweeps much faster (0.5 rad/s is 3 degrees a URG-04LX revolution).
const YAW_RATE_RAD_S: f32 = 0.5;
/// Time to stop from cruise and head back, s: the velocity loop's lag and a deceleration
/// from the field's 0.5 m/s, with the replan of the way home.
const TURN_BACK_S: f32 = 2.0;
/// Quality of a matched pose and of a predicted one (the autopilot refuses below 20).
const QUALITY_MATCHED: u8 = 80;
const QUALITY_PREDICTED: u8 = 10;

/// How the vehicle chooses where to go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Seed 002: follow the walls (the heading rules choose).
    WallFollow,
    /// The nearest reachable frontier of the SLAM map, the leg to it flown by the field.
    #[default]
    Frontier,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::WallFollow => "wall-follow",
            Strategy::Frontier => "frontier",
        }
    }
}

/// Where the companion is in the mission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Until the autopilot holds after take-off.
    Waiting,
    Exploring,
    Returning,
    /// The way home made no progress even after replanning: asking to land in place.
    LandingHere,
    /// The autopilot is landing: only poses are sent; once it is down, nothing.
    Finished,
}

/// Why exploring ended, for the summary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExploreEnd {
    Explorer(DoneReason),
    /// The time left covered only the way home.
    TimeBudget,
    /// Down a blank stretch, the way back to where the position was last seen only just
    /// fitted in the flight part's degraded bound ([`BlindBudget`]).
    BlindBudget,
}

/// What the companion did, kept for the score and the plots.
#[derive(Clone, Debug, Default)]
pub struct CompanionLog {
    /// Time exploring ended and why.
    pub explore_end: Option<(f64, ExploreEnd)>,
    /// Revolutions whose scan match failed (the pose was predicted).
    pub predicted: usize,
    /// Time flown between revolutions whose scan match saw a degenerate direction (the pose fix
    /// was unobserved along it), summed, s.
    pub degenerate_s: f64,
    /// Map corrections that moved the pose (reset counter bumps).
    pub resets: usize,
    /// Revolutions the live map could not take in.
    pub map_errors: usize,
    /// Length of the last planned way home, m.
    pub path_home_m: Option<f32>,
    /// Times the way home made no progress and was planned again round where it stalled.
    pub stall_replans: usize,
    /// When the way home was given up for want of progress, s.
    pub gave_up_s: Option<f64>,
    /// The landing was asked for off the home point: home was too near what the scan saw
    /// (a drifted map frame puts it against a wall) or not safely reachable.
    pub landed_off_home: bool,
}

/// SLAM, explorer and guidance of one flight.
pub struct ExploreCompanion<'m, const N: usize> {
    slam: Slam<'m, N>,
    explorer: Rc<RefCell<Explorer>>,
    guidance: Guidance<WALL_SEGMENTS>,
    strategy: Strategy,
    /// Whether the vehicle turns to the guidance's heading (a lidar with a blind sector).
    turns: bool,
    /// The flight must be back on the ground by then, s.
    end_s: f64,
    phase: Phase,
    /// The way home and when it was planned.
    home_path: Option<(f64, Option<Path>)>,
    /// The progress of the way home, from the start of the return.
    home_progress: Option<ProgressWatch>,
    last: Option<ScanPose>,
    /// The flight part's motion since the previous revolution: the SLAM's motion guess.
    motion: EstimatedMotion,
    /// Time of the previous revolution, s.
    last_t_s: Option<f64>,
    reset_counter: u8,
    /// Whether the way back from a blank stretch still fits in the flight part's bound.
    blind: BlindBudget,
    log: Rc<RefCell<CompanionLog>>,
}

impl<'m, const N: usize> ExploreCompanion<'m, N> {
    /// A companion flying `strategy` until `end_s` at the latest; the explorer and the log are
    /// shared with the caller, who reads them after the flight.
    pub fn new(
        slam: Slam<'m, N>,
        explorer: Rc<RefCell<Explorer>>,
        guidance: GuidanceConfig,
        strategy: Strategy,
        turns: bool,
        end_s: f64,
        log: Rc<RefCell<CompanionLog>>,
    ) -> Result<Self, String> {
        let guidance = Guidance::new(guidance).map_err(|e| e.to_string())?;
        Ok(Self {
            slam,
            explorer,
            guidance,
            strategy,
            turns,
            end_s,
            phase: Phase::Waiting,
            home_path: None,
            home_progress: None,
            last: None,
            motion: EstimatedMotion::default(),
            last_t_s: None,
            reset_counter: 0,
            blind: BlindBudget::new(
                EkfConfig::default().degraded_max_position_std_m,
                TURN_BACK_S,
            ),
            log,
        })
    }

    /// The pose fix for `at`, with the reset counter bumped when a map correction moved the
    /// keyframe the previous scan was anchored to.
    fn fix(&mut self, t_s: f64, at: &ScanPose) -> PoseFix {
        if self.last.is_some_and(|last| self.slam.map_jumped(&last)) {
            self.reset_counter = self.reset_counter.wrapping_add(1);
            self.log.borrow_mut().resets += 1;
        }
        PoseFix {
            t_s,
            position_m: [at.pose.x, at.pose.y],
            yaw_rad: at.pose.theta,
            covariance: fix_covariance(at.observed.and_then(|o| o.degenerate_direction)),
            quality_pct: Some(if at.predicted {
                QUALITY_PREDICTED
            } else {
                QUALITY_MATCHED
            }),
            reset_counter: self.reset_counter,
        }
    }

    /// The way home from `pose`, planned again when the last plan is older than
    /// [`HOME_PLAN_EVERY_S`].
    fn path_home(&mut self, t_s: f64, pose: Pose2) -> Option<&Path> {
        let fresh = self
            .home_path
            .as_ref()
            .is_some_and(|(t, _)| t_s - t < HOME_PLAN_EVERY_S);
        if !fresh {
            let path = self.explorer.borrow_mut().path_home(pose);
            self.log.borrow_mut().path_home_m = path.as_ref().map(|p| p.length_m);
            self.home_path = Some((t_s, path));
        }
        self.home_path.as_ref().and_then(|(_, p)| p.as_ref())
    }

    /// A velocity setpoint from the field toward `mode`'s goal.
    fn fly(
        &mut self,
        t_s: f64,
        scan: &Scan<N>,
        pose: Pose2,
        mode: GuidanceMode,
    ) -> CompanionSetpoint {
        let cmd = self.guidance.step(scan, pose, mode);
        // The heading turns toward the guidance's at most at YAW_RATE_RAD_S, and not at all
        // with a lidar that sees all round: the field is flown in the world frame, so turning
        // would buy nothing and cost the scan matcher accuracy.
        let dt = self
            .last_t_s
            .map_or(0.0, |t| (t_s - t) as f32)
            .clamp(0.0, 1.0);
        let step = if self.turns { YAW_RATE_RAD_S * dt } else { 0.0 };
        let turn = cmd
            .yaw_rad
            .map_or(0.0, |y| normalize_angle(y - pose.theta).clamp(-step, step));
        CompanionSetpoint {
            t_s,
            target: SetpointTarget::Velocity {
                velocity_m_s: cmd.velocity_world_m_s,
                yaw_rad: normalize_angle(pose.theta + turn),
            },
        }
    }

    /// Exploring: the next setpoint, or the decision to go home.
    /// Exploring also ends while the way back from a blank stretch still fits in the flight
    /// part's degraded bound (`way_back_fits`, [`BlindBudget`]).
    fn explore(
        &mut self,
        t_s: f64,
        scan: &Scan<N>,
        pose: Pose2,
        way_back_fits: bool,
        msgs: &mut CompanionMessages,
    ) {
        let home_m = self.path_home(t_s, pose).map(|p| p.length_m);
        msgs.path_home_m = home_m;
        // Without a way home on the map (yet) the straight line is the best guess.
        let straight = || {
            let home = self.explorer.borrow().home();
            home.map_or(0.0, |h| (h - pose.translation()).norm())
        };
        let home_m = f64::from(home_m.unwrap_or_else(straight));
        let out_of_time = t_s + home_m / RETURN_SPEED_M_S + RETURN_RESERVE_S >= self.end_s;
        let step = self.explorer.borrow_mut().next(pose);
        let end = match step {
            ExploreStep::Done(reason) => Some(ExploreEnd::Explorer(reason)),
            _ if out_of_time => Some(ExploreEnd::TimeBudget),
            _ if !way_back_fits => Some(ExploreEnd::BlindBudget),
            ExploreStep::Waypoint(_) => None,
        };
        if let Some(end) = end {
            self.log.borrow_mut().explore_end = Some((t_s, end));
            self.phase = Phase::Returning;
            self.home_path = None;
            return self.go_home(t_s, scan, pose, msgs);
        }
        let mode = match (self.strategy, step) {
            (Strategy::Frontier, ExploreStep::Waypoint(w)) => GuidanceMode::TowardWaypoint {
                world_m: [w.x, w.y],
            },
            _ => GuidanceMode::WallFollow,
        };
        msgs.setpoint = Some(self.fly(t_s, scan, pose, mode));
    }

    /// Returning: the path home flown by the field, the home point itself at the end.
    fn go_home(&mut self, t_s: f64, scan: &Scan<N>, pose: Pose2, msgs: &mut CompanionMessages) {
        msgs.command = Some(MissionCommand::ExploreDone);
        let Some(home) = self.explorer.borrow().home() else {
            return;
        };
        let p = pose.translation();
        let mut path = self.path_home(t_s, pose).cloned();
        let remaining_m = path.as_ref().map_or((home - p).norm(), |p| p.length_m);
        let watch = self
            .home_progress
            .get_or_insert_with(|| ProgressWatch::new(t_s, remaining_m));
        match watch.check(t_s, remaining_m) {
            Verdict::Progressing => {}
            Verdict::Replan => {
                // Where the vehicle was heading is where the map and the walls disagree.
                let stalled_at = path
                    .as_ref()
                    .map_or(home, |w| w.lookahead(p, HOME_LOOKAHEAD_M));
                self.explorer.borrow_mut().block(stalled_at);
                self.log.borrow_mut().stall_replans += 1;
                self.home_path = None;
                path = self.path_home(t_s, pose).cloned();
            }
            Verdict::GiveUp => {
                self.log.borrow_mut().gave_up_s = Some(t_s);
                self.phase = Phase::LandingHere;
                msgs.command = Some(MissionCommand::LandHere);
                return;
            }
        }
        msgs.path_home_m = path.as_ref().map(|p| p.length_m);
        if (home - p).norm() <= HOME_APPROACH_M {
            // The autopilot lands anywhere within its home tolerance of where it is sent, so
            // the spot keeps r_min plus that tolerance from what the scan sees.
            let g = self.guidance.config();
            let tolerance_m = MissionConfig::default().home_tolerance_m;
            let spot = landing_spot(
                scan,
                pose,
                home,
                g.r_min_m() + tolerance_m,
                g.vehicle_radius_m,
                HOME_APPROACH_M,
            );
            match spot {
                Some(spot) if spot == home || (spot - p).norm() > tolerance_m => {
                    msgs.setpoint = Some(CompanionSetpoint {
                        t_s,
                        target: SetpointTarget::Position {
                            position_m: [spot.x, spot.y],
                            yaw_rad: pose.theta,
                        },
                    });
                }
                // At a spot moved off home (the autopilot would not call it home), or with no
                // safe spot near home: down here, where the field has kept the vehicle clear.
                _ => {
                    self.log.borrow_mut().landed_off_home = true;
                    self.phase = Phase::LandingHere;
                    msgs.command = Some(MissionCommand::LandHere);
                }
            }
            return;
        }
        let target: Vec2 = path.map_or(home, |path| {
            let mut explorer = self.explorer.borrow_mut();
            explorer.lookahead_on(&path, p, HOME_LOOKAHEAD_M)
        });
        let mode = GuidanceMode::TowardWaypoint {
            world_m: [target.x, target.y],
        };
        msgs.setpoint = Some(self.fly(t_s, scan, pose, mode));
    }
}

impl<const N: usize> CompanionComputer<N> for ExploreCompanion<'_, N> {
    fn revolution(&mut self, scan: &Scan<N>, flight: &FlightLog) -> CompanionMessages {
        let t_s = scan.stamp_s;
        let mode = flight.final_mode();
        if self.phase == Phase::Finished
            && matches!(mode, FlightMode::Disarmed | FlightMode::Killed)
        {
            // Down for good: the mission's map is complete, and a companion that went on
            // mapping from the floor would spend its time re-optimising around whatever walks by.
            return CompanionMessages::default();
        }
        let at = self
            .slam
            .add_scan(scan, self.motion.since_last(&flight.last_estimate));
        if self
            .explorer
            .borrow_mut()
            .observe(&self.slam, scan, &at)
            .is_err()
        {
            self.log.borrow_mut().map_errors += 1;
        }
        let mut msgs = CompanionMessages {
            pose: Some(self.fix(t_s, &at)),
            ..CompanionMessages::default()
        };
        let [sx, sy, _] = flight.last_estimate.position_std_m;
        let way_back_fits = self.blind.update(t_s, [sx, sy]);
        {
            let mut log = self.log.borrow_mut();
            log.predicted += usize::from(at.predicted);
            let airborne = !matches!(mode, FlightMode::Disarmed | FlightMode::Killed);
            if airborne
                && at
                    .observed
                    .is_some_and(|o| o.degenerate_direction.is_some())
            {
                log.degenerate_s += self.last_t_s.map_or(0.0, |t| t_s - t);
            }
        }
        self.last = Some(at);
        if matches!(mode, FlightMode::Land | FlightMode::Killed)
            || (mode == FlightMode::Disarmed && self.phase != Phase::Waiting)
        {
            self.phase = Phase::Finished;
        }
        match self.phase {
            Phase::Waiting if mode == FlightMode::Hold => {
                self.phase = Phase::Exploring;
                msgs.command = Some(MissionCommand::StartExplore);
                self.explore(t_s, scan, at.pose, way_back_fits, &mut msgs);
            }
            Phase::Exploring => {
                if mode == FlightMode::Hold {
                    msgs.command = Some(MissionCommand::StartExplore);
                }
                self.explore(t_s, scan, at.pose, way_back_fits, &mut msgs);
            }
            Phase::Returning => self.go_home(t_s, scan, at.pose, &mut msgs),
            // No setpoint: the autopilot holds where it is until it takes up the landing.
            Phase::LandingHere => msgs.command = Some(MissionCommand::LandHere),
            Phase::Waiting | Phase::Finished => {}
        }
        self.last_t_s = Some(t_s);
        msgs
    }
}
