//! The onboard flight stack of `plumbline-core` ([`Onboard`]: lidar odometry, EKF, cascaded
//! PID, mixer, modes and failsafes) behind the runner's [`FlightSoftware`] interface, with a
//! scripted pilot's radio and lidar failure injection (what the closed-loop scenarios script).
//!
//! A companion computer ([`CompanionComputer`]: SLAM, exploration, guidance) may ride along
//! ([`WithCompanion`]): it sees each revolution as the stack does and its messages reach the
//! autopilot in the same step, as a wired link would deliver them between two steps.
//!
//! A ground station ([`GroundStation`]) may be linked too: it sees what the vehicle reports after
//! each step and its messages reach the autopilot at the next one.
//!
//! The runner consumes the flight software, so what the stack did (modes, failsafes, its
//! estimate, motor commands) is written into a shared [`FlightLog`] the caller keeps a handle
//! to. The runner never hands the stack ground truth; the log holds only onboard values.

use crate::runner::ground::{GroundLink, GroundStation, VehicleReport};
use crate::runner::mission::Mission;
use crate::runner::{FlightSoftware, SensorFrame, SetupError, STATE_RATE_HZ};
use crate::sensors::lidar::{LidarProfile, LidarScan};
use crate::vehicle::{Frame, VehicleParams};
use plumbline_core::control::airframe::Airframe;
use plumbline_core::control::mrac::FallbackReason;
use plumbline_core::flight::autopilot::AutopilotConfig;
use plumbline_core::flight::onboard::Onboard;
use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{
    CompanionMessages, EstimatedState, FailsafeReason, FlightMode, FrameKind, GroundMessages,
    ImuSample, Inputs, MotorCommands, PilotInput,
};
use plumbline_core::scan::{Beam, Scan};
use std::cell::RefCell;
use std::rc::Rc;

/// Onboard scan capacity for the XV-11 (360 beams): the smallest stack, as flown on hardware.
pub const XV11_BEAMS: usize = 360;
/// Onboard scan capacity for the Hokuyos (URG-04LX 667, UTM-30LX 1,081 beams), with room for
/// a 0.25-degree full-circle scanner.
pub const LARGE_SCAN_BEAMS: usize = 1440;

/// Rate the onboard loop runs at, Hz (the IMU's rate, so every step sees a fresh sample).
pub const ONBOARD_RATE_HZ: f64 = 500.0;

/// The autopilot configured for a simulated vehicle: its airframe in the onboard terms.
pub fn autopilot_for(v: &VehicleParams) -> AutopilotConfig {
    let frame = match v.frame {
        Frame::X => FrameKind::X,
        Frame::Plus => FrameKind::Plus,
    };
    AutopilotConfig::for_airframe(&Airframe {
        frame,
        mass_kg: v.mass_kg as f32,
        inertia_kgm2: v.inertia_kgm2.map(|i| i as f32),
        arm_length_m: v.arm_length_m as f32,
        max_thrust_n: (v.thrust_coeff * v.max_rotor_speed_radps * v.max_rotor_speed_radps) as f32,
        yaw_moment_per_thrust_m: (v.moment_coeff / v.thrust_coeff) as f32,
    })
}

/// What the pilot and the fault injector do during a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// (time, radio state) changes, in time order: the radio holds each state until the next
    /// one. Before the first the switches are off and the sticks centred.
    pub radio: Vec<(f64, PilotInput)>,
    /// The lidar stops delivering revolutions from this time on.
    pub lidar_dies_at_s: Option<f64>,
    /// Setpoints streamed to the stack while the mission lasts.
    pub mission: Option<Mission>,
}

impl Script {
    /// A pilot who flips the arm switch on at `t_s` and leaves the rest to the autopilot.
    pub fn arm_at(t_s: f64) -> Self {
        Self {
            radio: vec![(
                t_s,
                PilotInput {
                    arm: true,
                    ..PilotInput::default()
                },
            )],
            lidar_dies_at_s: None,
            mission: None,
        }
    }

    /// The radio's state at `t_s`.
    pub fn radio_at(&self, t_s: f64) -> PilotInput {
        self.radio
            .iter()
            .rev()
            .find(|(t, _)| *t <= t_s)
            .map_or(PilotInput::default(), |(_, p)| *p)
    }
}

/// The onboard outputs at one instant, sampled at the runner's [`STATE_RATE_HZ`] for plots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OnboardSample {
    pub t_s: f64,
    pub mode: FlightMode,
    pub estimate: EstimatedState,
    pub motors: [f32; 4],
}

/// What the onboard stack did during a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlightLog {
    /// Every mode change, with its time.
    pub modes: Vec<(f64, FlightMode)>,
    /// The most recent failsafe reason reported, kept after the failsafe clears.
    pub failsafe: Option<FailsafeReason>,
    /// The estimate after the last step (estimate frame: origin and heading at power-up).
    pub last_estimate: EstimatedState,
    pub samples: Vec<OnboardSample>,
    /// Scan points the matcher's dynamic-object test rejected (seed 000 sec. 4.2).
    pub rejected_points: u64,
    /// Time the mixer had to cut the controller's request to fit the motors, s.
    pub saturation_s: f64,
    /// How much later than planned the script's mission started (it waits for Hold), s;
    /// `None` when the stack never held, so the mission never started.
    pub mission_shift_s: Option<f64>,
    /// The MRAC's adaptive weight norm at the end and at its largest (`None` with the PID).
    pub adaptive_weight_norm: Option<f64>,
    pub max_adaptive_weight_norm: Option<f64>,
    /// When and why the MRAC's adaptive element first fell back to the baseline, if it did.
    pub adaptive_fallback: Option<(f64, FallbackReason)>,
    /// Sum over Hold steps and motors of the squared rate of change of the command, 1/s^2.
    jitter_sum: f64,
    jitter_terms: u64,
    previous_motors: Option<[f32; 4]>,
}

impl FlightLog {
    /// RMS rate of change of the motor commands while holding, 1/s (DESIGN.md §6 "control
    /// jitter"). Only Hold counts, so takeoff and landing ramps do not mask how busy the
    /// controller is on station. `None` when the vehicle never held.
    pub fn motor_jitter(&self) -> Option<f64> {
        (self.jitter_terms > 0).then(|| (self.jitter_sum / self.jitter_terms as f64).sqrt())
    }

    /// The mode at the end of the run.
    pub fn final_mode(&self) -> FlightMode {
        self.modes.last().map_or(FlightMode::Disarmed, |m| m.1)
    }

    fn record(&mut self, dt_s: f64, mode: FlightMode, motors: [f32; 4]) {
        if let (FlightMode::Hold, Some(prev)) = (mode, self.previous_motors) {
            if dt_s > 0.0 {
                for (now, before) in motors.iter().zip(prev) {
                    let rate = f64::from(now - before) / dt_s;
                    self.jitter_sum += rate * rate;
                    self.jitter_terms += 1;
                }
            }
        }
        self.previous_motors = Some(motors);
    }
}

/// [`Onboard`] for scans of up to `N` beams, flown by a [`Script`].
pub struct OnboardLink<const N: usize> {
    onboard: Box<Onboard<N>>,
    script: Script,
    /// The newest IMU sample; the runner calls at the IMU's rate, so it is rarely stale.
    last_imu: ImuSample,
    /// The revolution being handed over, in the onboard format.
    scan: Box<Scan<N>>,
    next_sample_s: f64,
    /// Set when the stack first holds: how much later than planned the mission flies.
    mission_shift_s: Option<f64>,
    log: Rc<RefCell<FlightLog>>,
    ground: Option<GroundLink>,
}

impl<const N: usize> OnboardLink<N> {
    /// A stack for `lidar`'s scans; fails when a revolution has more beams than `N`, rather
    /// than flying on silently truncated scans.
    pub fn new(
        lidar: &LidarProfile,
        odometry: OdometryConfig,
        autopilot: AutopilotConfig,
        script: Script,
    ) -> Result<(Self, Rc<RefCell<FlightLog>>), SetupError> {
        if lidar.beams > N {
            return Err(SetupError::Config(format!(
                "lidar {} has {} beams; the onboard stack holds {N}",
                lidar.name, lidar.beams
            )));
        }
        let log = Rc::new(RefCell::new(FlightLog::default()));
        let link = Self {
            onboard: Box::new(Onboard::new(odometry, autopilot)),
            script,
            last_imu: ImuSample::default(),
            scan: Box::new(Scan::new(0.0)),
            next_sample_s: 0.0,
            mission_shift_s: None,
            log: log.clone(),
            ground: None,
        };
        Ok((link, log))
    }
}

/// Writes the simulator's revolution into `scan` as an onboard scan; the device's validity
/// flags are kept. In place: a 1,440-beam scan is 23 kB, and returning one by value copied it
/// twice per revolution.
pub fn fill_scan<const N: usize>(s: &LidarScan, scan: &mut Scan<N>) {
    scan.clear(s.stamp_s);
    for (k, (&r, &ok)) in s.ranges_m.iter().zip(&s.valid).take(N).enumerate() {
        let angle = (s.start_angle_rad + s.increment_rad * k as f64) as f32;
        let mut beam = if ok {
            Beam::new(angle, r)
        } else {
            Beam::invalid(angle)
        };
        beam.time_offset_s = (s.beam_dt_s * k as f64) as f32;
        // At most N beams are taken (and `new` checked the profile), so the scan cannot be full.
        let _ = scan.push(beam);
    }
}

/// The companion computer's side of the link: it receives each revolution (in the onboard
/// format, as the flight part gets it) with what the flight part has reported so far, and
/// answers with its messages for the flight part.
pub trait CompanionComputer<const N: usize> {
    fn revolution(&mut self, scan: &Scan<N>, flight: &FlightLog) -> CompanionMessages;
}

impl<const N: usize> OnboardLink<N> {
    /// One onboard step; `companion`, when there is one, answers each new revolution first.
    fn step_with(
        &mut self,
        frame: &SensorFrame<'_>,
        dt_s: f64,
        companion: Option<&mut dyn CompanionComputer<N>>,
    ) -> MotorCommands {
        if let Some(s) = frame.imu.last() {
            self.last_imu = *s;
        }
        let lidar_alive = self.script.lidar_dies_at_s.is_none_or(|t| frame.t_s < t);
        let scan = match frame.scans.last() {
            Some(s) if lidar_alive => {
                fill_scan(s, &mut self.scan);
                Some(&*self.scan)
            }
            _ => None,
        };
        let messages = match (scan, companion) {
            (Some(scan), Some(c)) => c.revolution(scan, &self.log.borrow()),
            _ => CompanionMessages::default(),
        };
        let inputs = Inputs {
            t_s: frame.t_s,
            imu: self.last_imu,
            sonar: frame.sonar,
            scan_match: None,
            battery: Some(frame.battery),
            pilot: self.script.radio_at(frame.t_s),
            mission: self.mission_shift_s.and_then(|shift| {
                let m = self.script.mission.as_ref()?;
                m.setpoint(frame.t_s - shift)
            }),
            companion: messages,
            ground: self
                .ground
                .as_mut()
                .map_or(GroundMessages::default(), |g| g.uplink()),
        };
        let out = self.onboard.step(&inputs, scan, dt_s as f32);
        if let Some(ground) = self.ground.as_mut() {
            let report = VehicleReport {
                t_s: frame.t_s,
                outputs: &out,
                imu: self.last_imu,
                battery: frame.battery,
                sonar: frame.sonar,
                scan: scan.map(|s| s.beams()),
                events: &[],
                events_missed: 0,
            };
            ground.exchange(report, self.onboard.autopilot_mut());
        }
        if let (None, Some(m), FlightMode::Hold) =
            (self.mission_shift_s, &self.script.mission, out.mode)
        {
            self.mission_shift_s = Some(m.shift_for(frame.t_s));
        }
        let mut log = self.log.borrow_mut();
        log.mission_shift_s = self.mission_shift_s;
        if log.modes.last().is_none_or(|(_, m)| *m != out.mode) {
            log.modes.push((frame.t_s, out.mode));
        }
        log.failsafe = out.failsafe.or(log.failsafe);
        log.last_estimate = out.estimate;
        log.rejected_points = self.onboard.rejected_points();
        let autopilot = self.onboard.autopilot();
        log.saturation_s = autopilot.faults().saturated_s;
        // The norm after disarm is the forgotten one (zero): report the flight's.
        if let Some(mrac) = autopilot
            .mrac()
            .filter(|_| out.mode != FlightMode::Disarmed)
        {
            let norm = f64::from(mrac.weight_norm());
            log.adaptive_weight_norm = Some(norm);
            log.max_adaptive_weight_norm =
                Some(log.max_adaptive_weight_norm.map_or(norm, |m| m.max(norm)));
            if log.adaptive_fallback.is_none() {
                log.adaptive_fallback = mrac.fallback().map(|r| (frame.t_s, r));
            }
        }
        log.record(dt_s, out.mode, out.motors.throttle_norm);
        if frame.t_s >= self.next_sample_s {
            self.next_sample_s = frame.t_s + 1.0 / STATE_RATE_HZ;
            log.samples.push(OnboardSample {
                t_s: frame.t_s,
                mode: out.mode,
                estimate: out.estimate,
                motors: out.motors.throttle_norm,
            });
        }
        out.motors
    }
}

impl<const N: usize> FlightSoftware for OnboardLink<N> {
    fn rate_hz(&self) -> f64 {
        ONBOARD_RATE_HZ
    }

    fn step(&mut self, frame: &SensorFrame<'_>, dt_s: f64) -> MotorCommands {
        self.step_with(frame, dt_s, None)
    }

    fn link_ground(
        &mut self,
        station: Box<dyn GroundStation>,
    ) -> Result<(), Box<dyn GroundStation>> {
        self.link_ground_station(station);
        Ok(())
    }
}

impl<const N: usize> OnboardLink<N> {
    /// Links `station` to the stack from the next step on, beside any linked before.
    pub fn link_ground_station(&mut self, station: Box<dyn GroundStation>) {
        let events = self.onboard.autopilot().events().total();
        self.ground
            .get_or_insert_with(|| GroundLink::new(events))
            .add(station);
    }
}

/// The onboard stack with a companion computer on board.
pub struct WithCompanion<'a, const N: usize> {
    pub link: OnboardLink<N>,
    pub companion: Box<dyn CompanionComputer<N> + 'a>,
}

impl<const N: usize> FlightSoftware for WithCompanion<'_, N> {
    fn rate_hz(&self) -> f64 {
        ONBOARD_RATE_HZ
    }

    fn step(&mut self, frame: &SensorFrame<'_>, dt_s: f64) -> MotorCommands {
        self.link.step_with(frame, dt_s, Some(&mut *self.companion))
    }

    fn link_ground(
        &mut self,
        station: Box<dyn GroundStation>,
    ) -> Result<(), Box<dyn GroundStation>> {
        self.link.link_ground_station(station);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scan_larger_than_the_stack_is_refused() {
        let v = VehicleParams::f450();
        let script = Script::default();
        let small = OnboardLink::<XV11_BEAMS>::new(
            &LidarProfile::utm30lx(),
            OdometryConfig::default(),
            autopilot_for(&v),
            script.clone(),
        );
        assert!(matches!(small, Err(SetupError::Config(m)) if m.contains("1081")));
        for lidar in [LidarProfile::urg04lx(), LidarProfile::utm30lx()] {
            let large = OnboardLink::<LARGE_SCAN_BEAMS>::new(
                &lidar,
                OdometryConfig::default(),
                autopilot_for(&v),
                script.clone(),
            );
            assert!(large.is_ok(), "{}", lidar.name);
        }
    }

    #[test]
    fn jitter_counts_only_hold_steps() {
        let mut log = FlightLog::default();
        log.record(0.002, FlightMode::Takeoff, [0.0; 4]);
        log.record(0.002, FlightMode::Takeoff, [0.5; 4]);
        assert_eq!(log.motor_jitter(), None);
        // Each motor moves 0.001 in 2 ms: 0.5 per second.
        log.record(0.002, FlightMode::Hold, [0.501; 4]);
        let j = log.motor_jitter().unwrap();
        assert!((j - 0.5).abs() < 1e-3, "{j}");
    }
}
