//! The lockstep runner: one fixed physics step at a time (default 1 kHz), sensors sampled at
//! their own rates inside it, and the flight software called at its own rate through one step
//! interface (DESIGN.md §1). Everything random draws from streams forked from one seed, and
//! nothing reads a clock, so a run is reproducible bit for bit.
//!
//! Speed: what runs at every step (the dynamics, the lidar's beams, the IMU, the sensors' due
//! checks) is marked for inlining into [`run`]'s loop. Every floating-point register is
//! caller-saved on x86-64, so an out-of-line call there costs the loop a save and reload of its
//! live state; inlining saved about 120 M of the office survey's 718 M instructions
//! (BENCHMARKS.md, "Simulator"). Work done at a few hertz stays out of line.

use crate::battery::{Battery, BatteryLevel};
use crate::clearance::ClearanceWatch;
use crate::disturb::{push_force, GustParams, Gusts, Push};
use crate::dynamics::{BodyState, Dynamics, Forcing};
use crate::math::{Quat, Vec3};
use crate::pilot::TestPilot;
use crate::plan::Plan;
use crate::power::{power, EnergyTally};
use crate::rng::Rng;
use crate::scene::{Cylinder, Scene};
use crate::sensors::imu::{Imu, ImuParams};
use crate::sensors::lidar::{Lidar, LidarProfile, LidarScan, SensorPose};
use crate::sensors::sonar::{Sonar, SonarParams};
use crate::vehicle::{VehicleParams, GRAVITY};
use crate::world::{Walker, World, WorldError};
use plumbline_core::msgs::{BatterySample, ImuSample, MotorCommands, SonarSample};

/// Everything a run needs.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub world: World,
    pub vehicle: VehicleParams,
    pub lidar: LidarProfile,
    pub imu: ImuParams,
    pub sonar: SonarParams,
    pub gusts: Option<GustParams>,
    pub pushes: Vec<Push>,
    /// Whether the world's walking people are present.
    pub people: bool,
    pub physics_hz: f64,
    pub seed: u64,
    /// Stop after this much simulated time even if the flight is not over, s.
    pub max_duration_s: f64,
}

impl SimConfig {
    /// Defaults: f450 vehicle, ADIS16365 IMU, MB1040 sonar, indoor gusts, people on, 1 kHz.
    pub fn new(world: World, lidar: LidarProfile, seed: u64) -> Self {
        Self {
            world,
            vehicle: VehicleParams::f450(),
            lidar,
            imu: ImuParams::adis16365(),
            sonar: SonarParams::mb1040(),
            gusts: Some(GustParams::indoor()),
            pushes: Vec::new(),
            people: true,
            physics_hz: 1000.0,
            seed,
            max_duration_s: 3600.0,
        }
    }
}

/// The true 3-D pose of the vehicle at an instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthPose {
    pub t_s: f64,
    pub position: Vec3,
    pub attitude: Quat,
}

/// A snapshot for plots and progress, taken at [`STATE_RATE_HZ`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateSample {
    pub t_s: f64,
    pub position: Vec3,
    pub reference: Option<Vec3>,
    /// Roll, pitch, yaw, rad.
    pub euler: [f64; 3],
    pub battery_v: f64,
    pub power_w: f64,
}

pub const STATE_RATE_HZ: f64 = 50.0;

/// Receives the sensor streams and ground truth as they are produced.
pub trait Recorder {
    fn scan(&mut self, _scan: &LidarScan, _truth: &TruthPose) {}
    fn imu(&mut self, _sample: &ImuSample) {}
    fn sonar(&mut self, _sample: &SonarSample) {}
    fn state(&mut self, _sample: &StateSample) {}
}

/// A recorder that keeps nothing (benchmarks, tests that only need the outcome).
pub struct Discard;
impl Recorder for Discard {}

/// What arrived since the flight software's previous step.
#[derive(Clone, Copy, Debug)]
pub struct SensorFrame<'a> {
    pub t_s: f64,
    pub imu: &'a [ImuSample],
    pub sonar: Option<SonarSample>,
    pub scans: &'a [LidarScan],
    pub battery: BatterySample,
}

/// The onboard software as the simulator drives it: the same `step(inputs, dt) -> outputs`
/// shape as on hardware. It never sees ground truth.
pub trait FlightSoftware {
    fn rate_hz(&self) -> f64;
    fn step(&mut self, sensors: &SensorFrame<'_>, dt_s: f64) -> MotorCommands;
}

/// Who flies.
pub enum Pilot {
    /// The ground-truth test pilot flying a scripted plan (simulator-only, see [`crate::pilot`]).
    Test(Plan),
    /// Onboard code; the run lasts `SimConfig::max_duration_s`.
    Onboard(Box<dyn FlightSoftware>),
}

/// Rate of the test pilot, Hz.
const TEST_PILOT_HZ: f64 = 250.0;
/// Rate of collision checks, gust updates and people motion, Hz.
const SLOW_HZ: f64 = 100.0;
/// Clearance is searched only this far (grid cells around the vehicle), m.
pub const CLEARANCE_CAP_M: f64 = 2.0;
/// Faster than this the state has diverged, m/s and rad/s.
const MAX_SPEED_MPS: f64 = 100.0;
const MAX_RATE_RADPS: f64 = 200.0;
/// Touching down faster than this breaks the vehicle, m/s.
const MAX_LANDING_SPEED_MPS: f64 = 2.0;

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Completed,
    Crashed { t_s: f64, reason: String },
    Diverged { t_s: f64 },
    BatteryExhausted { t_s: f64 },
}

/// The figures of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub status: Status,
    pub sim_seconds: f64,
    pub physics_steps: u64,
    pub scans: u64,
    pub energy: EnergyTally,
    /// Energy drawn from the cells (includes the pack's internal loss), Wh.
    pub battery_energy_wh: f64,
    pub battery_end_v: f64,
    pub battery_min_v: f64,
    pub battery_end_soc: f64,
    /// First time the loaded pack voltage fell below the low threshold, s.
    pub battery_low_at_s: Option<f64>,
    /// Smallest distance from the centre to a wall, capped at [`CLEARANCE_CAP_M`].
    pub min_clearance_m: f64,
    /// Horizontal distance from the plan's reference while airborne (test pilot only), m.
    pub rms_hold_error_m: Option<f64>,
    pub max_hold_error_m: Option<f64>,
    pub distance_flown_m: f64,
}

/// Setup errors, reported before the first step.
#[derive(Clone, Debug, PartialEq)]
pub enum SetupError {
    World(WorldError),
    Vehicle(crate::vehicle::ParamError),
    Config(String),
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SetupError::World(e) => write!(f, "world: {e}"),
            SetupError::Vehicle(e) => write!(f, "{e}"),
            SetupError::Config(s) => write!(f, "{s}"),
        }
    }
}

impl std::error::Error for SetupError {}

/// Stream identifiers for [`Rng::fork`].
mod stream {
    pub const LIDAR: u64 = 1;
    pub const IMU: u64 = 2;
    pub const SONAR: u64 = 3;
    pub const GUSTS: u64 = 4;
    pub const MISMATCH: u64 = 5;
}

fn people_at(walkers: &[Walker], t_s: f64, out: &mut Vec<Cylinder>) {
    out.clear();
    out.extend(walkers.iter().map(|w| Cylinder {
        center: w.position(t_s),
        radius_m: Walker::RADIUS_M,
        height_m: Walker::HEIGHT_M,
    }));
}

/// Flies one run to the end and reports it.
pub fn run(
    config: &SimConfig,
    mut pilot: Pilot,
    recorder: &mut dyn Recorder,
) -> Result<Outcome, SetupError> {
    let v = &config.vehicle;
    v.validate().map_err(SetupError::Vehicle)?;
    let world = &config.world;
    let start = [world.start[0], world.start[1]];
    world
        .check_free(start, v.radius_m, "start")
        .map_err(SetupError::World)?;
    if !(config.physics_hz.is_finite() && config.physics_hz >= 100.0) {
        return Err(SetupError::Config(format!(
            "physics rate {} Hz is below 100 Hz",
            config.physics_hz
        )));
    }
    let hz = config.physics_hz;
    let dt = 1.0 / hz;
    let scene = Scene::new(world);
    let mut clearance = ClearanceWatch::default();
    let mut mismatch_rng = Rng::fork(config.seed, stream::MISMATCH);
    let mismatch = core::array::from_fn(|_| 1.0 + v.motor_mismatch * mismatch_rng.gauss());
    let dynamics = Dynamics::new(v, mismatch, dt);
    let mut lidar = Lidar::new(
        config.lidar.clone(),
        Rng::fork(config.seed, stream::LIDAR),
        0.0,
    );
    let mut imu = Imu::new(config.imu.clone(), Rng::fork(config.seed, stream::IMU));
    let mut sonar = Sonar::new(config.sonar.clone(), Rng::fork(config.seed, stream::SONAR));
    let mut gusts = config
        .gusts
        .clone()
        .map(|g| Gusts::new(g, Rng::fork(config.seed, stream::GUSTS)));
    let mut battery = Battery::new(v.battery.clone());
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
    let control_dt = control_every as f64 * dt;
    let slow_every = (hz / SLOW_HZ).round().max(1.0) as u64;
    let state_every = (hz / STATE_RATE_HZ).round().max(1.0) as u64;
    // The steps at which each rate is next due (counters, not `k % every`: a 64-bit division
    // per rate per step is a measurable share of a 1 kHz step).
    let (mut slow_due, mut control_due, mut state_due) = (0u64, 0u64, state_every);
    let mut test_pilot = TestPilot::new(v)
        .ok_or_else(|| SetupError::Config("rotor layout cannot be inverted".into()))?;

    let mut s = BodyState::at_rest(world.start_position(), world.start[2]);
    let mut forcing = Forcing::default();
    let mut energy = EnergyTally::default();
    let mut out = Outcome {
        status: Status::Completed,
        sim_seconds: 0.0,
        physics_steps: 0,
        scans: 0,
        energy,
        battery_energy_wh: 0.0,
        battery_end_v: battery.voltage_v,
        battery_min_v: battery.voltage_v,
        battery_end_soc: battery.soc,
        battery_low_at_s: None,
        min_clearance_m: f64::INFINITY,
        rms_hold_error_m: None,
        max_hold_error_m: None,
        distance_flown_m: 0.0,
    };
    let (mut err2_sum, mut err_n, mut err_max) = (0.0, 0u64, 0.0f64);
    let mut imu_buf: Vec<ImuSample> = Vec::new();
    let mut scan_buf: Vec<LidarScan> = Vec::new();
    let mut sonar_new: Option<SonarSample> = None;
    let mut scan_truth = TruthPose {
        t_s: 0.0,
        position: s.position,
        attitude: s.attitude,
    };
    let mut reference = None;
    let mut k: u64 = 0;
    // The time of step k, worked out once per step (the end of one step is the start of the
    // next).
    let mut t = 0.0;
    loop {
        if t >= end_s {
            break;
        }
        // Slow processes: gusts, people, collision checks.
        if k == slow_due {
            slow_due += slow_every;
            if let Some(g) = gusts.as_mut() {
                g.advance(slow_every as f64 * dt);
            }
            people_at(walkers, t, &mut people);
            // Searched only when it could set a new minimum or mean a crash.
            let floor = out.min_clearance_m.max(v.radius_m);
            let p = [s.position.x, s.position.y];
            let c = clearance.below(&scene, p, CLEARANCE_CAP_M, floor);
            let c = c.unwrap_or(f64::INFINITY);
            out.min_clearance_m = out.min_clearance_m.min(c);
            if c < v.radius_m {
                out.status = Status::Crashed {
                    t_s: t,
                    reason: format!("hit a wall at ({:.2}, {:.2})", s.position.x, s.position.y),
                };
                break;
            }
            if s.position.z > world.ceiling_m - 0.05 {
                out.status = Status::Crashed {
                    t_s: t,
                    reason: "hit the ceiling".into(),
                };
                break;
            }
        }
        // Flight software at its own rate.
        if k == control_due {
            control_due += control_every;
            let cmd = match &mut pilot {
                Pilot::Test(plan) => {
                    let r = plan.at(t);
                    if r.position.z > 0.3 {
                        let (ex, ey) = (r.position.x - s.position.x, r.position.y - s.position.y);
                        let e = (ex * ex + ey * ey).sqrt();
                        err2_sum += e * e;
                        err_n += 1;
                        err_max = err_max.max(e);
                    }
                    reference = Some(r.position);
                    test_pilot.command(&s, &r, control_dt)
                }
                Pilot::Onboard(fs) => {
                    let frame = SensorFrame {
                        t_s: t,
                        imu: &imu_buf,
                        sonar: sonar_new.take(),
                        scans: &scan_buf,
                        battery: BatterySample {
                            t_s: t,
                            voltage_v: battery.voltage_v as f32,
                        },
                    };
                    let m = fs.step(&frame, control_dt);
                    imu_buf.clear();
                    scan_buf.clear();
                    m.throttle_norm
                        .map(|c| if c.is_finite() { c as f64 } else { 0.0 })
                }
            };
            forcing.command = cmd;
        }
        forcing.wind = gusts.as_ref().map_or(Vec3::ZERO, |g| g.wind());
        forcing.force = push_force(&config.pushes, t);

        // Physics.
        let (position_before, velocity_before) = (s.position, s.velocity);
        s = dynamics.step(&s, &forcing);
        k += 1;
        // Through i64 (k < 2^63): SSE2 converts only signed integers, and `u64 as f64` costs
        // five instructions a step to this one (same value).
        t = k as i64 as f64 / hz;
        if !s.is_finite()
            || s.velocity.dot(s.velocity) > MAX_SPEED_MPS * MAX_SPEED_MPS
            || s.rate.dot(s.rate) > MAX_RATE_RADPS * MAX_RATE_RADPS
        {
            out.status = Status::Diverged { t_s: t };
            break;
        }
        if s.position.z < 0.0 {
            if -s.velocity.z > MAX_LANDING_SPEED_MPS {
                out.status = Status::Crashed {
                    t_s: t,
                    reason: format!("hit the floor at {:.1} m/s", -s.velocity.z),
                };
                break;
            }
            s.position.z = 0.0;
            s.velocity = Vec3::ZERO;
            s.rate = Vec3::ZERO;
            s.attitude = Quat::from_euler(0.0, 0.0, s.attitude.yaw());
        }
        out.distance_flown_m += (s.position - position_before).norm();

        // Power and battery.
        let omega_dot = dynamics.rotor_acceleration(&s);
        let split = power(v, &s.rotor_speed, &omega_dot);
        let power_w = split.total_w();
        energy.add(&split, dt);
        let level = battery.draw(power_w, dt);
        out.battery_min_v = out.battery_min_v.min(battery.voltage_v);
        if level != BatteryLevel::Ok && out.battery_low_at_s.is_none() {
            out.battery_low_at_s = Some(t);
        }
        if level == BatteryLevel::Exhausted {
            out.status = Status::BatteryExhausted { t_s: t };
            break;
        }

        // Sensors.
        let axes = s.attitude.axes();
        let accel = (s.velocity - velocity_before) * hz + Vec3::Z * GRAVITY;
        let specific_force = Vec3::new(axes[0].dot(accel), axes[1].dot(accel), axes[2].dot(accel));
        if let Some(sample) = imu.sample(t, s.rate, specific_force) {
            recorder.imu(&sample);
            if matches!(pilot, Pilot::Onboard(_)) {
                imu_buf.push(sample);
            }
        }
        if let Some(sample) = sonar.sample(t, s.position, axes, &scene, &people) {
            recorder.sonar(&sample);
            sonar_new = Some(sample);
        }
        if lidar.revolution_due(t) {
            scan_truth = TruthPose {
                t_s: t,
                position: s.position,
                attitude: s.attitude,
            };
        }
        let pose = SensorPose {
            origin: s.position + axes[2] * v.lidar_offset_z_m,
            x_axis: axes[0],
            y_axis: axes[1],
        };
        if let Some(scan) = lidar.sample(t, &pose, &scene, &people) {
            out.scans += 1;
            recorder.scan(
                &scan,
                &TruthPose {
                    t_s: scan.stamp_s,
                    ..scan_truth
                },
            );
            if matches!(pilot, Pilot::Onboard(_)) {
                scan_buf.push(scan);
            }
        }
        if k == state_due {
            state_due += state_every;
            let (roll, pitch, yaw) = s.attitude.to_euler();
            recorder.state(&StateSample {
                t_s: t,
                position: s.position,
                reference,
                euler: [roll, pitch, yaw],
                battery_v: battery.voltage_v,
                power_w,
            });
        }
    }
    out.sim_seconds = k as f64 / hz;
    out.physics_steps = k;
    out.energy = energy;
    out.battery_energy_wh = battery.energy_wh;
    out.battery_end_v = battery.voltage_v;
    out.battery_end_soc = battery.soc;
    if err_n > 0 {
        out.rms_hold_error_m = Some((err2_sum / err_n as f64).sqrt());
        out.max_hold_error_m = Some(err_max);
    }
    Ok(out)
}
