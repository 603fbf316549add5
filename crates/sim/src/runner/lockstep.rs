//! One run's state between physics steps, and the step itself: slow processes (gusts, people,
//! collisions), the pilot at its rate, the rigid body, power and battery, then the sensors.
//!
//! Speed: every method of the step is `#[inline(always)]`, so [`Lockstep::step`] compiles into
//! the loop of [`super::run`] as one body. Every floating-point register is caller-saved on
//! x86-64, so an out-of-line call there costs the loop a save and reload of its live state
//! (inlining saves about 120 M of the office survey's 718 M instructions, BENCHMARKS.md
//! "Simulator").

use super::config::{SetupError, SimConfig};
use super::report::{
    Outcome, Recorder, StateSample, Status, TruthPose, CLEARANCE_CAP_M, STATE_RATE_HZ,
};
use super::software::{Pilot, SensorFrame};
use crate::disturb::{push_force, Gusts};
use crate::math::{Quat, Vec3};
use crate::rng::Rng;
use crate::runner::pilot::TestPilot;
use crate::sensors::imu::Imu;
use crate::sensors::lidar::{Lidar, LidarScan, SensorPose};
use crate::sensors::sonar::Sonar;
use crate::vehicle::battery::{Battery, BatteryLevel};
use crate::vehicle::dynamics::{BodyState, Dynamics, Forcing};
use crate::vehicle::power::{power, EnergyTally};
use crate::vehicle::still_hover::StillHover;
use crate::vehicle::GRAVITY;
use crate::world::clearance::ClearanceWatch;
use crate::world::scene::{Cylinder, Scene};
use crate::world::Walker;
use plumbline_core::msgs::{BatterySample, ImuSample, SonarSample};

/// Rate of the test pilot, Hz.
const TEST_PILOT_HZ: f64 = 250.0;
/// Rate of collision checks, gust updates and people motion, Hz.
const SLOW_HZ: f64 = 100.0;
/// Faster than this the state has diverged, m/s and rad/s.
const MAX_SPEED_MPS: f64 = 100.0;
const MAX_RATE_RADPS: f64 = 200.0;
/// Touching down faster than this breaks the vehicle, m/s.
const MAX_LANDING_SPEED_MPS: f64 = 2.0;

/// Stream identifiers for [`Rng::fork`].
mod stream {
    pub const LIDAR: u64 = 1;
    pub const IMU: u64 = 2;
    pub const SONAR: u64 = 3;
    pub const GUSTS: u64 = 4;
    pub const MISMATCH: u64 = 5;
}

/// A step either goes on or ends the run with this status.
type Step = Result<(), Status>;

/// The steps at which each rate is next due. Counters, not `k % every`: a 64-bit division per
/// rate per step is a measurable share of a 1 kHz step.
struct Schedule {
    slow_every: u64,
    control_every: u64,
    state_every: u64,
    slow_due: u64,
    control_due: u64,
    state_due: u64,
}

/// Samples that arrived since the onboard software's previous step.
#[derive(Default)]
struct Inbox {
    imu: Vec<ImuSample>,
    scans: Vec<LidarScan>,
    sonar: Option<SonarSample>,
}

/// The emulated sensors.
struct Sensors {
    lidar: Lidar,
    imu: Imu,
    sonar: Sonar,
}

pub(super) struct Lockstep<'c> {
    config: &'c SimConfig,
    hz: f64,
    dt: f64,
    /// The run stops at this time, s.
    end_s: f64,
    schedule: Schedule,
    scene: Scene,
    clearance: ClearanceWatch,
    sensors: Sensors,
    gusts: Option<Gusts>,
    battery: Battery,
    walkers: &'c [Walker],
    people: Vec<Cylinder>,
    pilot: Pilot<'c>,
    test_pilot: TestPilot,
    forcing: Forcing,
    energy: EnergyTally,
    out: Outcome,
    inbox: Inbox,
    /// The truth at the start of the lidar revolution in progress.
    scan_truth: TruthPose,
    /// The test pilot's latest reference position.
    reference: Option<Vec3>,
    /// Each rotor's random thrust mismatch, kept to rebuild the dynamics when the body
    /// changes (a payload's release).
    mismatch: [f64; 4],
    /// Physics steps taken.
    k: u64,
    /// The time of step `k`, worked out once per step (the end of one step is the start of the
    /// next).
    t: f64,
}

fn people_at(walkers: &[Walker], t_s: f64, out: &mut Vec<Cylinder>) {
    out.clear();
    out.extend(walkers.iter().map(|w| Cylinder {
        center: w.position(t_s),
        radius_m: Walker::RADIUS_M,
        height_m: Walker::HEIGHT_M,
    }));
}

impl<'c> Lockstep<'c> {
    /// Checks the configuration; returns the run, the vehicle's dynamics and its true state, at
    /// rest at the world's start. The dynamics and the state are the loop's, not the run's:
    /// the run's address reaches code the compiler cannot see (the test pilot, the recorder),
    /// so anything inside it is reloaded from memory after each such call, while separate
    /// locals keep the dynamics' constants and cache and the state in registers (7 % of the
    /// survey's instructions).
    pub(super) fn new(
        config: &'c SimConfig,
        pilot: Pilot<'c>,
    ) -> Result<(Self, Dynamics, BodyState), SetupError> {
        let test_pilot = config.validate()?;
        let (v, world) = (&config.vehicle, &config.world);
        let hz = config.physics_hz;
        let dt = 1.0 / hz;
        let mut mismatch_rng = Rng::fork(config.seed, stream::MISMATCH);
        let mismatch: [f64; 4] =
            core::array::from_fn(|_| 1.0 + v.motor_mismatch * mismatch_rng.gauss());
        let sensors = Sensors {
            lidar: Lidar::new(
                config.lidar.clone(),
                Rng::fork(config.seed, stream::LIDAR),
                0.0,
            ),
            imu: Imu::new(config.imu.clone(), Rng::fork(config.seed, stream::IMU)),
            sonar: Sonar::new(config.sonar.clone(), Rng::fork(config.seed, stream::SONAR)),
        };
        let gusts = config
            .gusts
            .clone()
            .map(|g| Gusts::new(g, Rng::fork(config.seed, stream::GUSTS)));
        let battery = Battery::new(v.battery.clone());
        let walkers: &[Walker] = if config.people { &world.walkers } else { &[] };
        let mut people = Vec::new();
        people_at(walkers, 0.0, &mut people);

        let (control_every, end_s) = match &pilot {
            Pilot::Test(plan) => (
                (hz / TEST_PILOT_HZ).round().max(1.0) as u64,
                (plan.duration_s() + 1.0).min(config.max_duration_s),
            ),
            Pilot::Onboard(fs) => (
                (hz / fs.rate_hz()).round().max(1.0) as u64,
                config.max_duration_s,
            ),
        };
        let state_every = (hz / STATE_RATE_HZ).round().max(1.0) as u64;
        let schedule = Schedule {
            slow_every: (hz / SLOW_HZ).round().max(1.0) as u64,
            control_every,
            state_every,
            slow_due: 0,
            control_due: 0,
            state_due: state_every,
        };
        let s = BodyState::at_rest(world.start_position(), world.start[2]);
        let out = Outcome {
            status: Status::Completed,
            sim_seconds: 0.0,
            physics_steps: 0,
            scans: 0,
            energy: EnergyTally::default(),
            battery_energy_wh: 0.0,
            battery_end_v: battery.voltage_v,
            battery_min_v: battery.voltage_v,
            battery_end_soc: battery.soc,
            battery_low_at_s: None,
            min_clearance_m: f64::INFINITY,
            distance_flown_m: 0.0,
            still_hover: None,
        };
        let mut run = Self {
            config,
            hz,
            dt,
            end_s,
            schedule,
            scene: Scene::new(world),
            clearance: ClearanceWatch::default(),
            sensors,
            gusts,
            battery,
            walkers,
            people,
            pilot,
            test_pilot,
            scan_truth: TruthPose {
                t_s: 0.0,
                position: s.position,
                attitude: s.attitude,
            },
            forcing: Forcing::default(),
            energy: EnergyTally::default(),
            out,
            inbox: Inbox::default(),
            reference: None,
            mismatch,
            k: 0,
            t: 0.0,
        };
        let body = config.model_error.body(v, true);
        let dynamics = Dynamics::with_body(v, &body, mismatch, dt);
        run.out.still_hover = StillHover::of(v, &dynamics);
        Ok((run, dynamics, s))
    }

    /// The physics step at which the body changes (the model error's payload release).
    pub(super) fn body_change_step(&self) -> Option<u64> {
        let t = self.config.model_error.change_at_s()?;
        Some((t * self.hz).ceil() as u64)
    }

    /// The dynamics of the body after its change (the payload released).
    pub(super) fn dynamics_after_change(&self) -> Dynamics {
        let (config, v) = (self.config, &self.config.vehicle);
        let body = config.model_error.body(v, false);
        Dynamics::with_body(v, &body, self.mismatch, self.dt)
    }

    /// Physics steps taken so far.
    pub(super) fn steps(&self) -> u64 {
        self.k
    }

    /// Whether the flight has time left.
    #[inline(always)]
    pub(super) fn running(&self) -> bool {
        self.t < self.end_s
    }

    /// One physics step with everything due in it, in the order a real loop sees them: the
    /// world moves, the pilot commands from the state at the start of the step, the body
    /// integrates, the battery pays for it, and the sensors sample the new state.
    #[inline(always)]
    pub(super) fn step(
        &mut self,
        dynamics: &Dynamics,
        s: &mut BodyState,
        recorder: &mut dyn Recorder,
    ) -> Step {
        if self.k == self.schedule.slow_due {
            self.schedule.slow_due += self.schedule.slow_every;
            self.slow_processes(s)?;
        }
        if self.k == self.schedule.control_due {
            self.schedule.control_due += self.schedule.control_every;
            self.forcing.command = self.pilot_command(s, recorder);
        }
        self.forcing.wind = self.gusts.as_ref().map_or(Vec3::ZERO, |g| g.wind());
        self.forcing.force = push_force(&self.config.pushes, self.t);
        let velocity_before = self.advance_body(dynamics, s)?;
        let power_w = self.draw_power(dynamics, s)?;
        self.sense(s, velocity_before, recorder);
        if self.k == self.schedule.state_due {
            self.schedule.state_due += self.schedule.state_every;
            self.record_state(dynamics, s, power_w, recorder);
        }
        Ok(())
    }

    /// Gusts, people and the collision checks, at [`SLOW_HZ`].
    #[inline(always)]
    fn slow_processes(&mut self, s: &BodyState) -> Step {
        let (t, radius_m) = (self.t, self.config.vehicle.radius_m);
        if let Some(g) = self.gusts.as_mut() {
            g.advance(self.schedule.slow_every as f64 * self.dt);
        }
        people_at(self.walkers, t, &mut self.people);
        // Searched only when it could set a new minimum or mean a crash.
        let floor = self.out.min_clearance_m.max(radius_m);
        let p = [s.position.x, s.position.y];
        let c = self.clearance.below(&self.scene, p, CLEARANCE_CAP_M, floor);
        let c = c.unwrap_or(f64::INFINITY);
        self.out.min_clearance_m = self.out.min_clearance_m.min(c);
        if c < radius_m {
            return Err(Status::Crashed {
                t_s: t,
                reason: format!("hit a wall at ({:.2}, {:.2})", s.position.x, s.position.y),
            });
        }
        if s.position.z > self.config.world.ceiling_m - 0.05 {
            return Err(Status::Crashed {
                t_s: t,
                reason: "hit the ceiling".into(),
            });
        }
        Ok(())
    }

    /// The motor commands of whoever flies: the test pilot from the truth, or the onboard
    /// software from the samples that arrived since its previous step.
    #[inline(always)]
    fn pilot_command(&mut self, s: &BodyState, recorder: &mut dyn Recorder) -> [f64; 4] {
        let (t, control_dt) = (self.t, self.schedule.control_every as f64 * self.dt);
        match &mut self.pilot {
            Pilot::Test(plan) => {
                let r = plan.at(t);
                recorder.tracking(t, s.position, r.position);
                self.reference = Some(r.position);
                self.test_pilot.command(s, &r, control_dt)
            }
            Pilot::Onboard(fs) => {
                let inbox = &mut self.inbox;
                let frame = SensorFrame {
                    t_s: t,
                    imu: &inbox.imu,
                    sonar: inbox.sonar.take(),
                    scans: &inbox.scans,
                    battery: BatterySample {
                        t_s: t,
                        voltage_v: self.battery.voltage_v as f32,
                    },
                };
                let m = fs.step(&frame, control_dt);
                inbox.imu.clear();
                inbox.scans.clear();
                m.throttle_norm
                    .map(|c| if c.is_finite() { c as f64 } else { 0.0 })
            }
        }
    }

    /// Integrates the rigid body over one step, advances the clock, and ends the run on a
    /// diverged state or a hard touchdown. Returns the velocity before the step (the IMU's
    /// acceleration is the difference).
    #[inline(always)]
    fn advance_body(&mut self, dynamics: &Dynamics, s: &mut BodyState) -> Result<Vec3, Status> {
        let (position_before, velocity_before) = (s.position, s.velocity);
        *s = dynamics.step(s, &self.forcing);
        self.k += 1;
        // Through i64 (k < 2^63): SSE2 converts only signed integers, and `u64 as f64` costs
        // five instructions a step to this one (same value).
        self.t = self.k as i64 as f64 / self.hz;
        if !s.is_finite()
            || s.velocity.dot(s.velocity) > MAX_SPEED_MPS * MAX_SPEED_MPS
            || s.rate.dot(s.rate) > MAX_RATE_RADPS * MAX_RATE_RADPS
        {
            return Err(Status::Diverged { t_s: self.t });
        }
        if s.position.z < 0.0 {
            if -s.velocity.z > MAX_LANDING_SPEED_MPS {
                return Err(Status::Crashed {
                    t_s: self.t,
                    reason: format!("hit the floor at {:.1} m/s", -s.velocity.z),
                });
            }
            s.position.z = 0.0;
            s.velocity = Vec3::ZERO;
            s.rate = Vec3::ZERO;
            s.attitude = Quat::from_euler(0.0, 0.0, s.attitude.yaw());
        }
        self.out.distance_flown_m += (s.position - position_before).norm();
        Ok(velocity_before)
    }

    /// The electrical power of this step drawn from the battery; ends the run when the pack
    /// is exhausted. Returns the power, W.
    #[inline(always)]
    fn draw_power(&mut self, dynamics: &Dynamics, s: &BodyState) -> Result<f64, Status> {
        let v = &self.config.vehicle;
        let omega_dot = dynamics.rotor_acceleration(s);
        let split = power(v, &s.rotor_speed, &omega_dot);
        let power_w = split.total_w();
        self.energy.add(&split, self.dt);
        let level = self.battery.draw(power_w, self.dt);
        self.out.battery_min_v = self.out.battery_min_v.min(self.battery.voltage_v);
        if level != BatteryLevel::Ok && self.out.battery_low_at_s.is_none() {
            self.out.battery_low_at_s = Some(self.t);
        }
        if level == BatteryLevel::Exhausted {
            return Err(Status::BatteryExhausted { t_s: self.t });
        }
        Ok(power_w)
    }

    /// Samples the IMU, sonar and lidar on the new state and hands what is due to the recorder
    /// and, for onboard software, to its inbox.
    #[inline(always)]
    fn sense(&mut self, s: &BodyState, velocity_before: Vec3, recorder: &mut dyn Recorder) {
        let t = self.t;
        let onboard = matches!(self.pilot, Pilot::Onboard(_));
        let axes = s.attitude.axes();
        let accel = (s.velocity - velocity_before) * self.hz + Vec3::Z * GRAVITY;
        let specific_force = Vec3::new(axes[0].dot(accel), axes[1].dot(accel), axes[2].dot(accel));
        if let Some(sample) = self.sensors.imu.sample(t, s.rate, specific_force) {
            recorder.imu(&sample);
            if onboard {
                self.inbox.imu.push(sample);
            }
        }
        let sonar = &mut self.sensors.sonar;
        if let Some(sample) = sonar.sample(t, s.position, axes, &self.scene, &self.people) {
            recorder.sonar(&sample);
            self.inbox.sonar = Some(sample);
        }
        let lidar = &mut self.sensors.lidar;
        if lidar.revolution_due(t) {
            self.scan_truth = TruthPose {
                t_s: t,
                position: s.position,
                attitude: s.attitude,
            };
        }
        let pose = SensorPose {
            origin: s.position + axes[2] * self.config.vehicle.lidar_offset_z_m,
            x_axis: axes[0],
            y_axis: axes[1],
        };
        if let Some(scan) = lidar.sample(t, &pose, &self.scene, &self.people) {
            self.out.scans += 1;
            recorder.scan(
                &scan,
                &TruthPose {
                    t_s: scan.stamp_s,
                    ..self.scan_truth
                },
            );
            if onboard {
                self.inbox.scans.push(scan);
            }
        }
    }

    /// A snapshot for plots and progress, at [`STATE_RATE_HZ`].
    #[inline(always)]
    fn record_state(
        &self,
        dynamics: &Dynamics,
        s: &BodyState,
        power_w: f64,
        recorder: &mut dyn Recorder,
    ) {
        let (roll, pitch, yaw) = s.attitude.to_euler();
        recorder.state(&StateSample {
            t_s: self.t,
            position: s.position,
            reference: self.reference,
            euler: [roll, pitch, yaw],
            battery_v: self.battery.voltage_v,
            power_w,
            energy_wh: self.energy.total_wh(),
            rotor_speed: s.rotor_speed,
            thrust_n: dynamics.thrusts(s).iter().sum(),
        });
    }

    /// The figures of the run, ended with `status`.
    pub(super) fn finish(self, status: Status) -> Outcome {
        Outcome {
            status,
            sim_seconds: self.k as f64 / self.hz,
            physics_steps: self.k,
            energy: self.energy,
            battery_energy_wh: self.battery.energy_wh,
            battery_end_v: self.battery.voltage_v,
            battery_end_soc: self.battery.soc,
            ..self.out
        }
    }
}
