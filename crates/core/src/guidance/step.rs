//! One guidance step per lidar revolution: segments, heading rules, velocity field, speed limit
//! and clearance guard, in that order, turned into a world-frame command.
//!
//! Degraded inputs give a hover command (zero velocity, heading held) and say why in
//! [`Outcome`]: a scan with no usable beam, a non-finite pose, a non-finite waypoint.

use super::config::{GuidanceConfig, GuidanceConfigError};
use super::evade::evade;
use super::field::{field_sum, FieldPart, FieldSum};
use super::guard::{guard_velocity, Guard};
use super::heading::{choose_heading, HeadingRule, SideClearance};
use super::memory::{NearMemory, Recall};
use super::movers::{Mover, Movers};
use super::prls::WallSegments;
use super::sweep::Sweep;
use crate::geom::{normalize_angle, Pose2, Vec2};
use crate::scan::Scan;
use core::f32::consts::FRAC_PI_2;
use libm::atan2f;

/// A turn-around is done once the body points within this of where it turned to, rad: the
/// yaw loop of a vehicle that turns settles well within it.
const TURN_DONE_RAD: f32 = 0.1;

/// What the guidance is asked to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GuidanceMode {
    /// Seed 002's wall following: the field and the heading rules choose the way.
    WallFollow,
    /// Fly toward a world point (x, y in m), e.g. the next leg of a planner's path; the field's
    /// repulsive part and the clearance guard still act.
    TowardWaypoint { world_m: [f32; 2] },
}

/// Why the command is what it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// No usable beam in the scan: hover, heading held.
    NoUsableBeams,
    /// The pose estimate is not finite: hover, heading held.
    InvalidEstimate,
    /// The waypoint is not finite: hover, heading held.
    InvalidWaypoint,
    /// Wall following under the given heading rule.
    WallFollow(HeadingRule),
    /// Flying toward the waypoint, this far away (m).
    TowardWaypoint { distance_m: f32 },
}

/// Everything the rules decided, for the flight log and the plots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    pub outcome: Outcome,
    /// Free width across the way ahead (nearest hit on either side of the followed wall's
    /// direction, or of the way to the waypoint), m.
    pub free_width_m: Option<f32>,
    /// True when the free width is under twice `r_goal` and the vehicle keeps to the middle.
    pub centred: bool,
    /// Gaps narrower than `min_gap_width_m` read as wall (flown past).
    pub narrow_gaps_flown_past: usize,
    /// `K_v` after the raise near obstacles, m²/s (0 when there was no field).
    pub gain_m2_s: f32,
    /// True when the speed limit shortened the command.
    pub speed_limited: bool,
    /// The mover sidestepped instead of what the rules asked (none closing in: `None`).
    pub mover: Option<Mover>,
    /// What the clearance guard did.
    pub guard: Guard,
}

/// The command for the flight part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuidanceCommand {
    /// Horizontal velocity in the world frame, m/s.
    pub velocity_world_m_s: [f32; 2],
    /// Heading to take, world frame, rad in (−π, π]; `None` keeps the current heading.
    pub yaw_rad: Option<f32>,
    /// Nearest usable range in the scan, m.
    pub nearest_range_m: Option<f32>,
    pub decision: Decision,
}

/// Seed 002's guidance with room for `S` wall segments per revolution (no heap).
#[derive(Clone, Debug)]
pub struct Guidance<const S: usize> {
    cfg: GuidanceConfig,
    walls: WallSegments<S>,
    memory: NearMemory,
    movers: Movers,
    /// Where the last turn-around turned the rules to, world frame, rad, until the body has
    /// turned there too: the rules look from it meanwhile (from body x without one).
    turned_rad: Option<f32>,
    /// A heading backwards of where the rules look, chosen on the previous revolution and not
    /// yet taken, world frame, rad.
    pending_rad: Option<f32>,
}

impl<const S: usize> Guidance<S> {
    /// Checks the configuration once, so a step never meets an unusable parameter.
    pub fn new(cfg: GuidanceConfig) -> Result<Self, GuidanceConfigError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            walls: WallSegments::default(),
            memory: NearMemory::default(),
            movers: Movers::default(),
            turned_rad: None,
            pending_rad: None,
        })
    }

    pub fn config(&self) -> &GuidanceConfig {
        &self.cfg
    }

    /// The segments and gaps of the last step's scan (for logs and plots).
    pub fn walls(&self) -> &WallSegments<S> {
        &self.walls
    }

    /// One step: `scan` in the body frame, `pose` the estimated world pose of the body. The
    /// scan's stamp is the clock of the near-hit memory (hits kept `obstacle_memory_s`, and up to
    /// `obstacle_hold_s` while the vehicle stays near where it saw them).
    pub fn step<const N: usize>(
        &mut self,
        scan: &Scan<N>,
        pose: Pose2,
        mode: GuidanceMode,
    ) -> GuidanceCommand {
        let cfg = self.cfg;
        if !pose.is_finite() {
            return hover(Outcome::InvalidEstimate, None);
        }
        if let GuidanceMode::TowardWaypoint { world_m } = mode {
            if !world_m.iter().all(|v| v.is_finite()) {
                return hover(Outcome::InvalidWaypoint, None);
            }
        }
        // Wall following looks from where a dead end turned it; the waypoint mode has no rules.
        let facing = match mode {
            GuidanceMode::WallFollow => self
                .turned_rad
                .map_or(0.0, |t| normalize_angle(t - pose.theta)),
            GuidanceMode::TowardWaypoint { .. } => 0.0,
        };
        let sweep = Sweep::new(scan, cfg.rule_start_rad + facing);
        self.walls.extract_sweep(&sweep, &cfg);
        let part = match mode {
            GuidanceMode::WallFollow => FieldPart::WallFollow,
            GuidanceMode::TowardWaypoint { .. } => FieldPart::Repulsive,
        };
        let Some(field) = field_sum(&sweep, &self.walls, &cfg, part) else {
            return hover(Outcome::NoUsableBeams, None);
        };
        let (wish_body, yaw_body, outcome, sides, centred) = match mode {
            GuidanceMode::WallFollow => {
                let choice = choose_heading(&self.walls, &sweep, facing, &cfg);
                let heading = self.turn(choice.body_rad, facing, pose.theta);
                let sides = SideClearance::measure(&sweep, Some(heading.unwrap_or(facing)));
                let centred = sides.is_narrow(&cfg);
                let v = if centred {
                    centred_velocity(&sides, &cfg)
                } else {
                    field.velocity_m_s
                };
                let outcome = Outcome::WallFollow(choice.rule);
                (v, heading, outcome, sides, centred)
            }
            GuidanceMode::TowardWaypoint { world_m } => {
                let (v, yaw, dist) = toward(pose, world_m, &field, &cfg);
                let sides = SideClearance::measure(&sweep, yaw);
                let outcome = Outcome::TowardWaypoint { distance_m: dist };
                (v, yaw, outcome, sides, false)
            }
        };
        let now = scan.stamp_s;
        let (limited, speed_limited) = limit_speed(wish_body, cfg.max_speed_m_s);
        let recall = Recall {
            memory_s: cfg.obstacle_memory_s,
            hold_s: cfg.obstacle_hold_s,
            hold_m: cfg.max_speed_m_s / cfg.approach_rate_1_s,
        };
        let remembered = self.memory.recalled(pose, now, recall);
        let recalled = || remembered.iter();
        // A mover closing in is stepped aside from; walls still bind through the guard.
        let mover = self.movers.closing(&sweep, pose, now, &cfg);
        let limited = match &mover {
            Some(m) => {
                let (v, side) = evade(m, limited, &sweep, recalled, &cfg, self.movers.side());
                self.movers.pass_on(side);
                v
            }
            None => limited,
        };
        let (safe, guard) = guard_velocity(limited, &sweep, recalled, &cfg);
        let guard_reach_m = cfg.r_min_m() + cfg.max_speed_m_s / cfg.approach_rate_1_s;
        self.memory.remember(&sweep, pose, now, guard_reach_m);
        let world = pose.rotate(safe);
        GuidanceCommand {
            velocity_world_m_s: [world.x, world.y],
            yaw_rad: yaw_body.map(|y| normalize_angle(pose.theta + y)),
            nearest_range_m: Some(field.nearest_range_m),
            decision: Decision {
                outcome,
                free_width_m: sides.free_width_m(),
                centred,
                narrow_gaps_flown_past: field.narrow_gaps,
                gain_m2_s: field.gain_m2_s,
                speed_limited,
                mover,
                guard,
            },
        }
    }
}

impl<const S: usize> Guidance<S> {
    /// The heading to fly (body frame; `None` holds it) for the rules' `chosen` one, looking
    /// from `facing` (body frame) with the body at `yaw_rad` (world).
    ///
    /// A chosen heading backwards of `facing` is a turn-around (a dead end, or the far side of
    /// a corridor's end past a door): it is taken when chosen on two revolutions running, and
    /// then the rules look from it until the body has turned there. One revolution's misreading
    /// (the far end of a corridor's wall lost at a grazing angle, a walker across the way)
    /// holds the heading for that revolution instead of turning the vehicle round.
    fn turn(&mut self, chosen: Option<f32>, facing: f32, yaw_rad: f32) -> Option<f32> {
        let backward = chosen
            .filter(|h| normalize_angle(h - facing).abs() > FRAC_PI_2)
            .map(|h| normalize_angle(yaw_rad + h));
        let again = |b: f32| {
            self.pending_rad
                .is_some_and(|p| normalize_angle(p - b).abs() <= FRAC_PI_2)
        };
        match backward {
            Some(b) if again(b) => {
                self.turned_rad = Some(b);
                self.pending_rad = None;
                chosen
            }
            Some(b) => {
                self.pending_rad = Some(b);
                None
            }
            None => {
                self.pending_rad = None;
                if facing.abs() <= TURN_DONE_RAD {
                    self.turned_rad = None;
                }
                chosen
            }
        }
    }
}

fn hover(outcome: Outcome, nearest_range_m: Option<f32>) -> GuidanceCommand {
    GuidanceCommand {
        velocity_world_m_s: [0.0, 0.0],
        yaw_rad: None,
        nearest_range_m,
        decision: Decision {
            outcome,
            free_width_m: None,
            centred: false,
            narrow_gaps_flown_past: 0,
            gain_m2_s: 0.0,
            speed_limited: false,
            mover: None,
            guard: Guard::Clear,
        },
    }
}

/// Seed 002, Fig. 5: in a passage narrower than twice `r_goal`, equal distance to both sides
/// while moving along the followed wall. The along-wall part never has a component across the
/// passage, so it cannot push into either side.
fn centred_velocity(sides: &SideClearance, cfg: &GuidanceConfig) -> Vec2 {
    let (Some(left), Some(right)) = (sides.left_m, sides.right_m) else {
        return Vec2::ZERO;
    };
    // Centring comes first, across the axis toward the side with more room; the speed left
    // under the limit goes along the axis (the followed wall's direction).
    let lateral_m_s =
        (cfg.centring_gain_1_s * 0.5 * (left - right)).clamp(-cfg.max_speed_m_s, cfg.max_speed_m_s);
    let spare = libm::sqrtf(cfg.max_speed_m_s * cfg.max_speed_m_s - lateral_m_s * lateral_m_s);
    sides.axis * cfg.cruise_speed_m_s.min(spare) + sides.axis.perp() * lateral_m_s
}

/// Toward a waypoint: attraction capped at the cruise speed plus the field's repulsive part.
/// Returns the body-frame velocity, the heading to the waypoint (body frame) and the distance.
fn toward(
    pose: Pose2,
    world_m: [f32; 2],
    field: &FieldSum,
    cfg: &GuidanceConfig,
) -> (Vec2, Option<f32>, f32) {
    let to_world = Vec2::new(world_m[0] - pose.x, world_m[1] - pose.y);
    let dist = to_world.norm();
    let to_body = pose.inverse().rotate(to_world);
    let speed = (cfg.waypoint_gain_1_s * dist).min(cfg.cruise_speed_m_s);
    let attraction = if dist > 1e-6 {
        to_body * (speed / dist)
    } else {
        Vec2::ZERO
    };
    // Turning on the spot near the waypoint only wastes time and smears the scan.
    let yaw = (dist > cfg.vehicle_radius_m).then(|| atan2f(to_body.y, to_body.x));
    (attraction + field.velocity_m_s, yaw, dist)
}

fn limit_speed(v: Vec2, max_m_s: f32) -> (Vec2, bool) {
    let speed = v.norm();
    if speed > max_m_s {
        (v * (max_m_s / speed), true)
    } else {
        (v, false)
    }
}
