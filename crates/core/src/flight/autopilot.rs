//! The autopilot: owns the onboard state and runs one step of the loop (DESIGN.md §1).
//!
//! `step(inputs, dt) -> outputs` reads top to bottom in the order of the loop: sense, estimate,
//! supervise, guide, control, mix. It never reads a clock, a file or a socket, so the simulator,
//! the log replayer and the hardware runner drive exactly the same code. It never panics: a bad
//! input is counted in [`FaultCounters`] and the step degrades (damped, level, or stopped) with
//! finite motor commands.

use super::events::{EventKind, EventLog};
use super::mission::Mission;
use super::supervisor::{Status, Supervisor, EVENT_LOG_LEN};
use crate::control::cascade::{Cascade, CascadeSetpoint, Vertical};
use crate::control::mixer::{Demand, Mixer};
use crate::control::mrac::{FallbackReason, Mrac, AUTOPILOT_CENTRES};
use crate::control::sas;
use crate::estimate::ekf::Outcome;
use crate::estimate::estimator::{Estimator, EstimatorCounters, Situation};
use crate::estimate::pose_fix::CompanionFrame;
use crate::guidance::nearest_hits::NearestHits;
use crate::msgs::{
    CommandResult, EstimatedState, FailsafeReason, FlightMode, GroundAck, GroundCommand, Inputs,
    MotorCommands, Outputs, PilotInput, PositionSetpoint, Refusal, ScanMatchStatus,
};

pub use super::autopilot_config::{AutopilotConfig, ControllerKind, LandingConfig};

/// Faults the autopilot survived, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaultCounters {
    /// Steps with a non-finite, non-positive or too long `dt`.
    pub bad_dt: u32,
    /// Pilot stick values that were not finite (treated as centred / zero throttle).
    pub bad_pilot: u32,
    /// Battery readings that were not finite (ignored).
    pub bad_battery: u32,
    /// Steps where the cascade refused its inputs and rate damping alone flew.
    pub control_errors: u32,
    /// Steps where the mixer had to cut the request to fit the motors.
    pub mixer_saturated: u32,
    /// Mission setpoints with a non-finite value (ignored).
    pub bad_mission: u32,
    /// Time the mixer spent cutting requests, s (`mixer_saturated` in seconds).
    pub saturated_s: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Autopilot {
    pub config: AutopilotConfig,
    estimator: Estimator,
    supervisor: Supervisor,
    cascade: Cascade,
    mixer: Mixer,
    mission: Mission,
    /// Hold point and heading: set at takeoff and when the pilot hands back control.
    home: PositionSetpoint,
    /// Where the vehicle took off (world x, y): where a mission returns to.
    takeoff_xy: [f32; 2],
    mode: FlightMode,
    saturated: bool,
    /// Last step's collective was below `landing.low_thrust_fraction` of hover.
    low_thrust: bool,
    faults: FaultCounters,
    last: Outputs,
    /// The latest revolution's nearest hits, against which mission setpoints are guarded.
    nearest_hits: Option<NearestHits>,
}

impl Autopilot {
    /// The autopilot for `config`. An MRAC configuration that fails its validation is not
    /// flown: the PID cascade flies instead and the event log starts with
    /// [`FallbackReason::InvalidConfig`] (check [`MracConfig::validate`] first to refuse it).
    pub fn new(config: AutopilotConfig) -> Self {
        let mut supervisor = Supervisor::new(config.supervisor);
        let cascade = match config.controller {
            ControllerKind::Pid => Cascade::new(config.cascade),
            ControllerKind::Mrac => {
                Cascade::with_mrac(config.cascade, config.mrac).unwrap_or_else(|_| {
                    let reason = FallbackReason::InvalidConfig;
                    supervisor.record(0.0, EventKind::AdaptiveFallback(reason));
                    Cascade::new(config.cascade)
                })
            }
        };
        Self {
            config,
            estimator: Estimator::new(config.estimator),
            supervisor,
            cascade,
            mixer: Mixer::new(config.frame),
            mission: Mission::new(config.mission),
            home: PositionSetpoint::default(),
            takeoff_xy: [0.0; 2],
            mode: FlightMode::Disarmed,
            saturated: false,
            low_thrust: false,
            faults: FaultCounters::default(),
            last: Outputs::default(),
            nearest_hits: None,
        }
    }

    /// What the last step returned (all zeros and disarmed before the first step).
    pub fn last_outputs(&self) -> &Outputs {
        &self.last
    }

    pub fn faults(&self) -> &FaultCounters {
        &self.faults
    }

    /// Takes in the nearest hits of a revolution that just completed: the mission setpoints
    /// are guarded against them until the next one.
    pub fn observe_hits(&mut self, hits: NearestHits) {
        self.nearest_hits = Some(hits);
    }

    pub fn estimator_counters(&self) -> &EstimatorCounters {
        self.estimator.counters()
    }

    pub fn events(&self) -> &EventLog<EVENT_LOG_LEN> {
        self.supervisor.events()
    }

    /// The MRAC flying the outer loops, if it does (its weight norm, hedge and fallback).
    pub fn mrac(&self) -> Option<&Mrac<AUTOPILOT_CENTRES>> {
        self.cascade.mrac()
    }

    /// The exploration mission's state and refused companion inputs.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// The companion's map frame (its anchor) and the pose-fix tallies.
    pub fn companion_frame(&self) -> &CompanionFrame {
        self.estimator.companion_frame()
    }

    /// One pass of the onboard loop.
    pub fn step(&mut self, inputs: &Inputs, dt: f32) -> Outputs {
        // ---- sense: sanitise what the vehicle handed us ----
        let pilot = self.sanitise_pilot(inputs.pilot);
        // SAFETY-CRITICAL: the kill switch stops the motors even when nothing else can run.
        // Plain comparisons (a NaN fails them): `is_finite` is several integer operations.
        if !(dt > 0.0 && dt <= self.config.landing.max_dt_s && dt < f32::INFINITY) {
            self.faults.bad_dt = self.faults.bad_dt.saturating_add(1);
            let command = inputs.ground.command;
            if command == Some(GroundCommand::Terminate) {
                self.supervisor.terminate();
            }
            if pilot.kill || self.supervisor.terminated() {
                self.last.motors = MotorCommands::STOPPED;
                self.last.mode = FlightMode::Killed;
            }
            self.last.ground_ack = command.map(|command| GroundAck {
                command,
                result: match command {
                    GroundCommand::Terminate => CommandResult::Accepted,
                    _ => CommandResult::Refused(Refusal::StepNotRun),
                },
            });
            return self.last;
        }
        let battery_v = match inputs.battery.map(|b| b.voltage_v) {
            Some(v) if !v.is_finite() => {
                self.faults.bad_battery = self.faults.bad_battery.saturating_add(1);
                None
            }
            other => other,
        };

        // ---- estimate: IMU prediction, then the measurements that arrived ----
        self.estimator.predict(&inputs.imu, dt);
        if let Some(sonar) = &inputs.sonar {
            self.estimator.fuse_sonar(sonar);
        }
        let scan_accepted = inputs.scan_match.is_some_and(|m| {
            // The match is handed over when its revolution completes; its pose is that of
            // mid-revolution, half-way from its first beam (`t_s`) to now.
            let latency_s = (0.5 * (inputs.t_s - m.t_s)) as f32;
            let outcome = self.estimator.fuse_scan_match(&m, latency_s);
            m.status == ScanMatchStatus::Matched && outcome == Outcome::Accepted
        });
        if let Some(fix) = &inputs.companion.pose {
            self.estimator
                .fuse_pose_fix(fix, (inputs.t_s - fix.t_s) as f32);
        }
        self.estimator.fuse_situation(&Situation {
            disarmed: self.mode == FlightMode::Disarmed,
            rotors_carry: matches!(
                self.mode,
                FlightMode::Takeoff
                    | FlightMode::Hold
                    | FlightMode::Explore
                    | FlightMode::Return
                    | FlightMode::Land
                    | FlightMode::Manual
            ),
            lidar_lost: self.supervisor.failsafe() == Some(FailsafeReason::LidarLost),
            ground_height_m: self.config.landing.ground_height_m,
        });
        let estimate = self.estimator.state();
        let rates = self
            .estimator
            .body_rates(finite_or_zero(inputs.imu.gyro_rad_s));

        // ---- supervise: modes and failsafes ----
        self.mission
            .observe(inputs.t_s, &inputs.companion, battery_v, dt);
        let frame = *self.estimator.companion_frame();
        if matches!(
            self.mode,
            FlightMode::Takeoff | FlightMode::Hold | FlightMode::Explore | FlightMode::Return
        ) {
            self.mission.track_home(self.takeoff_xy, &frame);
        }
        let home_xy = self.mission.home(self.takeoff_xy, &frame);
        let c = &self.config;
        let landing_s = self.supervisor.hold_height_m() / c.landing.descent_m_s;
        let here_xy = [estimate.position_m[0], estimate.position_m[1]];
        let mission = self.mission.status(inputs.t_s, here_xy, home_xy, landing_s);
        let status = Status {
            t_s: inputs.t_s,
            pilot,
            estimate,
            horizontal: self.estimator.horizontal(),
            scan_accepted,
            battery_v,
            low_thrust: self.low_thrust,
            mission,
            ground: inputs.ground,
        };
        let mode = self.supervisor.update(&status);
        if mode != self.mode {
            // A return lands at the take-off point; any other mission landing where it is.
            let land_xy = if mission.at_home { home_xy } else { here_xy };
            self.enter(mode, &estimate, inputs.t_s, land_xy);
        }
        let ground_ack = self.supervisor.ack();
        if let Some(GroundAck {
            command: GroundCommand::Takeoff { .. },
            result: CommandResult::Accepted,
        }) = ground_ack
        {
            self.home.position_m[2] = self.supervisor.hold_height_m();
        }
        let failsafe = self.supervisor.failsafe();
        let pilot = *self.supervisor.pilot();

        // ---- guide: what this mode asks for ----
        let mission = self.follow(mode, inputs.mission);
        let mut setpoint = self.guide(mode, failsafe, &estimate, inputs.t_s);
        if let Some(sp) = setpoint.as_mut() {
            sp.feed_forward = mission;
        }

        // ---- control: cascade in the autonomous modes, rate damping in manual ----
        let airborne = estimate.position_m[2] > self.config.landing.ground_height_m;
        let demand = match (mode, setpoint) {
            // SAFETY-CRITICAL: disarmed and killed mean motors stopped, nothing else.
            (FlightMode::Disarmed | FlightMode::Killed, _) => None,
            (FlightMode::Manual, _) => Some(self.manual(&pilot, rates)),
            (_, Some(sp)) => {
                let integrate = airborne && !self.saturated;
                let demand = match self.cascade.run(&sp, &estimate, rates, dt, integrate) {
                    Ok(d) => d,
                    Err(_) => {
                        self.faults.control_errors = self.faults.control_errors.saturating_add(1);
                        self.damped_hover(rates)
                    }
                };
                if let Some(reason) = self.cascade.take_fallback() {
                    let event = EventKind::AdaptiveFallback(reason);
                    self.supervisor.record(inputs.t_s, event);
                }
                Some(demand)
            }
            (_, None) => Some(self.damped_hover(rates)),
        };

        // ---- mix ----
        let motors = match demand {
            Some(d) => {
                let hover = self.config.cascade.hover_collective;
                self.low_thrust = d.collective < self.config.landing.low_thrust_fraction * hover;
                let mixed = self.mixer.mix(d);
                self.saturated = mixed.saturated;
                if mixed.saturated {
                    self.faults.mixer_saturated = self.faults.mixer_saturated.saturating_add(1);
                    self.faults.saturated_s += f64::from(dt);
                }
                self.cascade.actuated(&mixed.achieved, airborne);
                mixed.motors
            }
            None => MotorCommands::STOPPED,
        };

        self.last = Outputs {
            motors,
            mode,
            failsafe,
            estimate,
            setpoint: setpoint.map(|sp| self.report(&sp, &estimate)),
            ground_ack,
        };
        self.last
    }

    /// Mode entry actions: capture the hold point (a mission's landing lands at `land_xy`),
    /// forget controller history.
    fn enter(&mut self, mode: FlightMode, e: &EstimatedState, t_s: f64, land_xy: [f32; 2]) {
        let here = PositionSetpoint {
            position_m: e.position_m,
            yaw_rad: e.yaw_rad,
        };
        match mode {
            FlightMode::Takeoff | FlightMode::Hold => {
                // Takeoff holds above where it left the ground; a hand-back, or a mission
                // stopped by the ground station or the link-lost failsafe, holds where it is.
                if matches!(
                    self.mode,
                    FlightMode::Manual | FlightMode::Explore | FlightMode::Return
                ) || mode == FlightMode::Takeoff
                {
                    self.home = here;
                }
                if mode == FlightMode::Takeoff {
                    self.takeoff_xy = [here.position_m[0], here.position_m[1]];
                }
                self.home.position_m[2] = self.supervisor.hold_height_m();
            }
            FlightMode::Land if matches!(self.mode, FlightMode::Explore | FlightMode::Return) => {
                self.home.position_m[0] = land_xy[0];
                self.home.position_m[1] = land_xy[1];
                self.home.yaw_rad = e.yaw_rad;
            }
            FlightMode::Disarmed | FlightMode::Killed => {
                self.saturated = false;
                self.cascade.forget_learning();
            }
            FlightMode::Land | FlightMode::Manual | FlightMode::Explore | FlightMode::Return => {}
        }
        self.mission.enter(mode, t_s);
        self.cascade.reset();
        self.mode = mode;
    }

    /// Manual flight: sticks through the rate damper (seed 002 eqs. 4-6), throttle as collective.
    fn manual(&self, pilot: &PilotInput, rates: [f32; 3]) -> Demand {
        let sticks = [pilot.roll_norm, pilot.pitch_norm, pilot.yaw_norm];
        let [roll, pitch, yaw] = sas::damp(&self.config.sas, sticks, rates);
        Demand {
            collective: pilot.throttle_norm.clamp(0.0, 1.0),
            roll,
            pitch,
            yaw,
        }
    }

    /// Fallback when the cascade cannot run: hover collective with rate damping, so the vehicle
    /// does not tumble while the supervisor decides.
    fn damped_hover(&self, rates: [f32; 3]) -> Demand {
        let [roll, pitch, yaw] = sas::damp(&self.config.sas, [0.0; 3], rates);
        Demand {
            collective: self.config.cascade.hover_collective,
            roll,
            pitch,
            yaw,
        }
    }

    /// The position setpoint as logged: the hold point, or where a landing is heading.
    fn report(&self, sp: &CascadeSetpoint, e: &EstimatedState) -> PositionSetpoint {
        let [x, y] = sp
            .horizontal_m
            .unwrap_or([e.position_m[0], e.position_m[1]]);
        let z = match sp.vertical {
            Vertical::Height(h) => h,
            Vertical::ClimbRate(_) => 0.0,
        };
        PositionSetpoint {
            position_m: [x, y, z],
            yaw_rad: sp.yaw_rad,
        }
    }

    fn sanitise_pilot(&mut self, mut p: PilotInput) -> PilotInput {
        let mut bad = false;
        for v in [
            &mut p.roll_norm,
            &mut p.pitch_norm,
            &mut p.yaw_norm,
            &mut p.throttle_norm,
        ] {
            if !v.is_finite() {
                *v = 0.0;
                bad = true;
            }
        }
        if bad {
            self.faults.bad_pilot = self.faults.bad_pilot.saturating_add(1);
        }
        p
    }
}

#[path = "autopilot_params.rs"]
mod params_on_board;
#[path = "autopilot_setpoints.rs"]
mod setpoints;

fn finite_or_zero(v: [f32; 3]) -> [f32; 3] {
    v.map(|x| if x.is_finite() { x } else { 0.0 })
}
