//! Messages between the vehicle (simulated, replayed or real) and the onboard code.
//!
//! Plain `Copy` structs with the unit in every field name, so a driver written against these types
//! cannot mix up metres and centimetres or degrees and radians. Frames follow DESIGN.md §3: world
//! is ENU-like (z up), body is FLU (x forward, y left, z up). Times are seconds as `f64` (the
//! simulator's clock); onboard steps themselves take `dt: f32`.

/// Standard gravity; the simulator and the onboard code must agree on it.
pub const GRAVITY_M_S2: f32 = 9.806_65;

/// One inertial sample in the body FLU frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    pub t_s: f64,
    /// Angular rate about body x, y, z (right-handed, counter-clockwise positive).
    pub gyro_rad_s: [f32; 3],
    /// Specific force (what an accelerometer reads): +9.81 on z when resting level.
    pub accel_m_s2: [f32; 3],
}

/// One sonar range along body -z (down), from the sensor to the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SonarSample {
    pub t_s: f64,
    pub range_m: f32,
}

/// One battery measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BatterySample {
    pub t_s: f64,
    /// Pack voltage under load.
    pub voltage_v: f32,
}

/// What the scan matcher reports for one lidar revolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScanMatchStatus {
    /// No match was attempted (first scan, or the matcher started a new reference scan without
    /// matching); the scan becomes the reference for later matches.
    ReferenceOnly,
    /// The pose change fields hold a match of this scan against the current reference.
    Matched,
    /// The matcher ran and failed (too few points, no convergence); the pose change is meaningless.
    Failed,
}

/// The scan matcher's result for one revolution, as the estimator consumes it.
///
/// The pose change is the pose of this scan expressed in the frame of the *reference* scan (the
/// previous scan for scan-to-scan matching, or a keyframe), i.e. `inverse(x_ref) * x_now`.
/// The estimator keeps a copy of its pose at the reference time, so both kinds of matching work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanMatchDelta {
    /// Time the scan was taken.
    pub t_s: f64,
    pub status: ScanMatchStatus,
    /// Translation in the reference scan's frame.
    pub dx_m: f32,
    pub dy_m: f32,
    /// Rotation, normalised to (-pi, pi].
    pub dtheta_rad: f32,
    /// Covariance of (dx_m, dy_m, dtheta_rad); units m^2, m*rad, rad^2. Row-major, symmetric.
    /// With a `degenerate_axis` only the part across the axis counts (the variance along it
    /// may be zero or anything): the estimator uses the translation across it and the rotation.
    pub covariance: [[f32; 3]; 3],
    /// Unit vector (reference frame) along which the match could not constrain translation, e.g.
    /// the axis of a featureless corridor. `None` when all directions are observed.
    pub degenerate_axis: Option<[f32; 2]>,
    /// True when, after this result, this scan is the reference for the next matches
    /// (always for scan-to-scan; only on keyframe changes for scan-to-keyframe).
    pub becomes_reference: bool,
}

/// The pilot's radio: sticks normalised and switches.
///
/// Sticks are signed as on a Mode-2 radio, right (and up, forward) positive, so a pilot's
/// habits carry over: each stick's doc says which way the vehicle goes in FLU terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PilotInput {
    /// Roll stick, -1 (left) .. 1 (right). Right banks right: a positive roll about FLU x, the
    /// vehicle moves to its right (-y).
    pub roll_norm: f32,
    /// Pitch stick, -1 (back) .. 1 (forward). Forward tips the nose down: a positive pitch
    /// about FLU y, the vehicle moves forward (+x).
    pub pitch_norm: f32,
    /// Yaw stick, -1 (left) .. 1 (right). Right turns clockwise seen from above: a negative yaw
    /// rate about FLU z (z up).
    pub yaw_norm: f32,
    /// Throttle stick, 0 .. 1 (collective; up climbs).
    pub throttle_norm: f32,
    /// Arm switch: on arms and (outside manual) takes off; off lands and disarms once down.
    pub arm: bool,
    /// Manual takeover switch: stick flight with rate damping (seed 002 sec. II.B.2).
    pub manual: bool,
    /// Kill switch: motors stop at once, whatever else is going on (seed 002 sec. III).
    pub kill: bool,
}

/// Normalised motor commands, one per motor, in the order of [`FrameKind::motors`].
///
/// 0 is stopped, 1 is full; the command is proportional to rotor speed, so thrust goes with its
/// square (seed 002 eq. 20 takes a square root for this reason).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotorCommands {
    pub throttle_norm: [f32; 4],
}

impl MotorCommands {
    pub const STOPPED: MotorCommands = MotorCommands {
        throttle_norm: [0.0; 4],
    };
}

/// The two quadrotor frame layouts of seed 002 eq. 20 and its plus-configuration twin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameKind {
    /// Square ("X") configuration: motors on the diagonals.
    #[default]
    X,
    /// Plus configuration: motors on the body axes.
    Plus,
}

/// Where one motor sits and which way it turns; arm length is a vehicle parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorGeometry {
    /// Unit vector from the centre of gravity to the rotor hub, body FLU x and y.
    pub arm_dir: [f32; 2],
    /// True when the rotor turns counter-clockwise seen from above; its reaction torque on the
    /// body is then clockwise (negative about body z).
    pub spins_ccw: bool,
}

impl FrameKind {
    /// Motor order is seed 002's numbering: X = 1 front-right, 2 back-right, 3 back-left,
    /// 4 front-left; plus = 1 front, 2 right, 3 back, 4 left. Odd motors turn clockwise (eq. 19:
    /// yaw moment -M1 + M2 - M3 + M4). Index 0 here is the seed's motor 1.
    pub fn motors(self) -> [MotorGeometry; 4] {
        const D: f32 = core::f32::consts::FRAC_1_SQRT_2;
        let dirs = match self {
            FrameKind::X => [[D, -D], [-D, -D], [-D, D], [D, D]],
            FrameKind::Plus => [[1.0, 0.0], [0.0, -1.0], [-1.0, 0.0], [0.0, 1.0]],
        };
        let mut out = [MotorGeometry {
            arm_dir: [0.0; 2],
            spins_ccw: false,
        }; 4];
        for (i, m) in out.iter_mut().enumerate() {
            m.arm_dir = dirs[i];
            m.spins_ccw = i % 2 == 1;
        }
        out
    }
}

/// Where the autopilot wants the vehicle: a hold point and heading in the world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PositionSetpoint {
    pub position_m: [f32; 3],
    pub yaw_rad: f32,
}

/// A setpoint from a mission (MAVLink SET_POSITION_TARGET_LOCAL_NED: position, velocity,
/// acceleration, yaw), in the estimate frame. A sequence of them flies a path: each moves the
/// hold point, and its velocity and acceleration are fed forward so the vehicle keeps up with
/// it where it cruises and where it speeds up or slows down.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MissionSetpoint {
    pub position_m: [f32; 3],
    /// How fast the setpoint moves horizontally (m/s).
    pub velocity_m_s: [f32; 2],
    /// How fast that velocity changes (m/s^2).
    pub acceleration_m_s2: [f32; 2],
    pub yaw_rad: f32,
}

/// The onboard estimate, in the world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatedState {
    pub position_m: [f32; 3],
    pub velocity_m_s: [f32; 3],
    pub roll_rad: f32,
    pub pitch_rad: f32,
    pub yaw_rad: f32,
    /// One-sigma position uncertainty per world axis, from the filter's covariance.
    pub position_std_m: [f32; 3],
    /// False when the filter has diverged or has not been fed enough to fly on.
    pub valid: bool,
}

/// The autopilot's modes (DESIGN.md §1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FlightMode {
    /// Motors stopped, waiting for the arm switch.
    #[default]
    Disarmed,
    /// Climbing to the hold height above the takeoff point.
    Takeoff,
    /// Holding position and heading.
    Hold,
    /// Flying the companion's exploration setpoints (holding while they are stale).
    Explore,
    /// Flying the companion's path-home setpoints back to the take-off point.
    Return,
    /// Descending; disarms on touchdown.
    Land,
    /// Pilot sticks with rate damping.
    Manual,
    /// Kill switch or a ground terminate: motors stopped until the switch is released (or the
    /// ground station disarms) and the vehicle re-armed.
    Killed,
}

impl FlightMode {
    /// The mode's name in summaries, logs and ground-station texts.
    pub const fn name(self) -> &'static str {
        match self {
            FlightMode::Disarmed => "disarmed",
            FlightMode::Takeoff => "takeoff",
            FlightMode::Hold => "hold",
            FlightMode::Explore => "explore",
            FlightMode::Return => "return",
            FlightMode::Land => "land",
            FlightMode::Manual => "manual",
            FlightMode::Killed => "killed",
        }
    }
}

/// Why the autopilot overrode the pilot or the mission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailsafeReason {
    /// No usable scan match: held on the IMU for a bounded time, then landed.
    LidarLost,
    /// The estimate is not trustworthy (diverged, non-finite, too uncertain): land.
    EstimateInvalid,
    /// Battery below the landing threshold: land.
    BatteryLow,
    /// Battery below the critical threshold: land now, faster.
    BatteryCritical,
    /// The kill switch stopped the motors.
    KillSwitch,
    /// The companion sent no setpoint for too long during a mission: held, then landed.
    CompanionLost,
    /// A ground station that had been heard went silent (no heartbeat for
    /// `GroundConfig::link_timeout_s`), or its manual sticks stopped: held, then landed.
    LinkLost,
    /// The companion found the way home (or the leg it flew) making no progress, even after
    /// planning round the place it stalled at: landed where it was rather than hover until
    /// the battery runs down.
    NoProgress,
}

impl FailsafeReason {
    /// The failsafe's name in summaries and logs.
    pub const fn name(self) -> &'static str {
        match self {
            FailsafeReason::LidarLost => "lidar_lost",
            FailsafeReason::EstimateInvalid => "estimate_invalid",
            FailsafeReason::BatteryLow => "battery_low",
            FailsafeReason::BatteryCritical => "battery_critical",
            FailsafeReason::KillSwitch => "kill_switch",
            FailsafeReason::CompanionLost => "companion_lost",
            FailsafeReason::LinkLost => "link_lost",
            FailsafeReason::NoProgress => "no_progress",
        }
    }

    /// The failsafe in words, for a person (ground-station texts, the web view).
    pub const fn text(self) -> &'static str {
        match self {
            FailsafeReason::LidarLost => "lidar lost",
            FailsafeReason::EstimateInvalid => "estimate invalid",
            FailsafeReason::BatteryLow => "battery low",
            FailsafeReason::BatteryCritical => "battery critical",
            FailsafeReason::KillSwitch => "kill switch",
            FailsafeReason::CompanionLost => "companion lost",
            FailsafeReason::LinkLost => "ground link lost",
            FailsafeReason::NoProgress => "no progress: landing in place",
        }
    }
}

/// Everything the vehicle hands the autopilot for one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    /// The current time; the IMU sample is taken at this step.
    pub t_s: f64,
    pub imu: ImuSample,
    /// A new sonar reading, if one arrived since the last step.
    pub sonar: Option<SonarSample>,
    /// A new scan-matcher result, if a revolution completed since the last step.
    pub scan_match: Option<ScanMatchDelta>,
    /// A new battery reading, if one arrived since the last step.
    pub battery: Option<BatterySample>,
    pub pilot: PilotInput,
    /// This step's mission setpoint, if a mission is flying; followed in Hold only.
    pub mission: Option<MissionSetpoint>,
    /// What the companion computer sent since the last step (all `None` without one).
    pub companion: CompanionMessages,
    /// What the ground station sent since the last step (nothing without one).
    pub ground: GroundMessages,
}

/// What the autopilot hands back after one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs {
    pub motors: MotorCommands,
    pub mode: FlightMode,
    /// The most recent failsafe that is still in force.
    pub failsafe: Option<FailsafeReason>,
    pub estimate: EstimatedState,
    /// The position setpoint being flown, when the mode has one.
    pub setpoint: Option<PositionSetpoint>,
    /// The answer to this step's ground command, if one arrived (the link's COMMAND_ACK).
    pub ground_ack: Option<GroundAck>,
}

/// A pose from the companion computer's SLAM: where the vehicle is in the companion's map frame.
///
/// The content of MAVLink ODOMETRY (frame_id LOCAL_FRD, child_frame_id BODY_FRD, estimator_type
/// VISION) restricted to what a 2-D lidar SLAM knows; the MAVLink layer converts ENU/FLU to
/// NED/FRD. The map frame is the companion's: the autopilot anchors it to its own world frame
/// (a re-anchoring on every `reset_counter` change), so the two need not share an origin.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseFix {
    /// Time the pose belongs to, on the autopilot's clock: for a revolution deskewed to
    /// mid-revolution (as the onboard odometry does), the middle of the revolution, not its
    /// first beam; the fix is compared with the estimate taken back to this time.
    pub t_s: f64,
    /// Position in the companion's map frame (m).
    pub position_m: [f32; 2],
    /// Heading in the map frame, counter-clockwise from map x (rad).
    pub yaw_rad: f32,
    /// Covariance of (x, y, yaw); units m^2, m*rad, rad^2. Row-major, symmetric. A position
    /// direction the companion did not observe (a featureless corridor's axis) is said by a
    /// variance along it beyond the autopilot's bound (`PoseFixConfig::max_position_std_m`):
    /// the fix is then fused across it only. Keep that variance moderate (100 m^2 says it): in
    /// f32 a covariance a million times wider one way than the other is no longer positive
    /// definite once rotated, and is refused.
    pub covariance: [[f32; 3]; 3],
    /// Match quality 0 (unknown) to 100 (best); `None` when the SLAM is lost (MAVLink -1).
    pub quality_pct: Option<u8>,
    /// Bumped by the companion on every re-localisation (a jump of its pose); wraps at 255.
    pub reset_counter: u8,
}

/// What the companion asks the vehicle to fly on the current leg.
///
/// The content of MAVLink SET_POSITION_TARGET_LOCAL_NED in the companion's map frame: either a
/// position (type mask: position and yaw) or a horizontal velocity (velocity and yaw). Height
/// stays the autopilot's: the mission flies at the take-off hold height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SetpointTarget {
    /// Fly to and hold this map position (m) with this heading (rad).
    Position { position_m: [f32; 2], yaw_rad: f32 },
    /// Fly this map-frame horizontal velocity (m/s) with this heading (rad).
    Velocity {
        velocity_m_s: [f32; 2],
        yaw_rad: f32,
    },
}

/// One setpoint and when the companion made it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompanionSetpoint {
    /// Time the setpoint was computed, on the autopilot's clock; older than
    /// `MissionConfig::setpoint_timeout_s` counts as stale.
    pub t_s: f64,
    pub target: SetpointTarget,
}

/// Mission commands the companion sends (MAVLink COMMAND_LONG on the wire).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionCommand {
    /// Leave the hold after take-off and fly the exploration setpoints.
    StartExplore,
    /// Exploration is finished (coverage stopped growing, nothing reachable is left): return.
    ExploreDone,
    /// The mission cannot go on (no progress toward its goal, even after replanning): land in
    /// place.
    LandHere,
}

/// Everything the companion computer hands the flight part in one step; each part is optional
/// and independent (they arrive at their own rates).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompanionMessages {
    pub pose: Option<PoseFix>,
    pub setpoint: Option<CompanionSetpoint>,
    pub command: Option<MissionCommand>,
    /// Length of the planned path from here to the take-off point (m), for the battery
    /// decision; the latest one counts until a new one arrives.
    pub path_home_m: Option<f32>,
}

/// What a ground station asks of the vehicle (MAVLink COMMAND_LONG and MANUAL_CONTROL on the
/// wire), after the link layer has checked the target system and, with a key, the signature.
///
/// Plain values so the flight part never sees the wire format; the autopilot decides whether a
/// command is allowed in the current mode and the link reports that back (COMMAND_ACK).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GroundCommand {
    Arm,
    Disarm,
    /// Take off and hold; `None` keeps the configured hold height (m above the take-off floor).
    Takeoff {
        height_m: Option<f32>,
    },
    Land,
    /// Fly back to the take-off point and land.
    Return,
    SetMode(GroundMode),
    /// Flight termination, the remote kill switch: motors off at the next control step.
    Terminate,
    /// Manual takeover sticks, in the radio's conventions (see [`PilotInput`]).
    Sticks(GroundSticks),
}

/// The autonomous and manual modes a ground station may select.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroundMode {
    Hold,
    Explore,
    Manual,
}

/// Everything a ground station hands the flight part in one step, after the link layer has
/// decoded and checked it. At most one command per step: a link that received several queues
/// them, one per step (the kill switch first).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundMessages {
    pub command: Option<GroundCommand>,
    /// A ground-station heartbeat arrived since the last step: the link is alive. Once one has
    /// been heard, their absence raises the link-lost failsafe.
    pub heartbeat: bool,
}

/// The autopilot's answer to a [`GroundCommand`], given in the step that received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundAck {
    pub command: GroundCommand,
    pub result: CommandResult,
}

/// Whether a ground command was carried out (MAVLink COMMAND_ACK: `Accepted` is
/// MAV_RESULT_ACCEPTED, `Refused` TEMPORARILY_REJECTED, `InvalidParameter` DENIED).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandResult {
    /// Carried out this step (or already the case, e.g. arming an armed vehicle).
    Accepted,
    /// Not in the current mode or state; the same command may succeed later.
    Refused(Refusal),
    /// A parameter is not finite or outside its bounds (a take-off height, stick values).
    InvalidParameter,
}

/// Why a ground command was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// The current mode does not take this command.
    WrongMode,
    /// A disarm while flying: land instead.
    Airborne,
    /// The radio's manual or kill switch is on: the pilot on the radio is in charge.
    RadioInCharge,
    /// Exploring and returning follow a companion computer, and none is talking.
    NoCompanion,
    /// The estimate is not good enough to fly on autonomously.
    EstimateInvalid,
    /// The battery is critical: no arming.
    BatteryCritical,
    /// The motors are killed: only a disarm (releasing the latch) or a terminate is taken.
    Killed,
    /// A manual takeover needs recent sticks from the ground station first.
    NoSticks,
    /// The step that received it could not run (a bad time step): send it again.
    StepNotRun,
}

/// Stick positions from a ground station (MANUAL_CONTROL), normalised like [`PilotInput`]'s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundSticks {
    pub roll_norm: f32,
    pub pitch_norm: f32,
    pub yaw_norm: f32,
    pub throttle_norm: f32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_put_each_motor_on_a_unit_arm_with_alternating_spin() {
        for frame in [FrameKind::X, FrameKind::Plus] {
            let m = frame.motors();
            let (mut sx, mut sy, mut spin) = (0.0, 0.0, 0);
            for g in m {
                let n = libm::hypotf(g.arm_dir[0], g.arm_dir[1]);
                assert!((n - 1.0).abs() < 1e-6);
                sx += g.arm_dir[0];
                sy += g.arm_dir[1];
                spin += if g.spins_ccw { 1 } else { -1 };
            }
            // Balanced: no net lever arm, no net reaction torque at equal speeds.
            assert!(sx.abs() < 1e-6 && sy.abs() < 1e-6 && spin == 0);
        }
        // Seed 002 numbering: motor 1 front-right of an X frame, turning clockwise.
        let m1 = FrameKind::X.motors()[0];
        assert!(m1.arm_dir[0] > 0.0 && m1.arm_dir[1] < 0.0 && !m1.spins_ccw);
    }
}
