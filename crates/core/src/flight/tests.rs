//! Closed-loop tests of the whole autopilot against the small test vehicle.

extern crate std;

use super::autopilot::{Autopilot, AutopilotConfig};
use super::test_vehicle::{TestVehicle, AIRFRAME};
use crate::msgs::{FailsafeReason, FlightMode, Inputs, Outputs};
use libm::hypotf;

pub(super) const HZ: u64 = 500;
pub(super) const DT: f32 = 1.0 / HZ as f32;

pub(super) fn config() -> AutopilotConfig {
    AutopilotConfig::for_airframe(&AIRFRAME)
}

pub(super) struct Flight {
    pub(super) ap: Autopilot,
    pub(super) veh: TestVehicle,
    pub(super) step: u64,
    pub(super) out: Outputs,
    /// Fastest vertical speed at which the vehicle met the floor (m/s).
    worst_touchdown_m_s: f32,
}

impl Flight {
    pub(super) fn new(config: AutopilotConfig, seed: u64) -> Self {
        Self {
            ap: Autopilot::new(config),
            veh: TestVehicle::on_the_floor(seed),
            step: 0,
            out: Outputs::default(),
            worst_touchdown_m_s: 0.0,
        }
    }

    /// Flies `secs`, letting `tamper` change the inputs (it sees the vehicle's truth); calls `watch` after every step.
    pub(super) fn fly_with(
        &mut self,
        secs: f32,
        mut tamper: impl FnMut(&mut Inputs, &TestVehicle),
        mut watch: impl FnMut(&Outputs, &TestVehicle),
    ) {
        for _ in 0..(secs * HZ as f32) as u64 {
            self.step += 1;
            let mut inputs = self.veh.sense(self.step, HZ);
            tamper(&mut inputs, &self.veh);
            self.out = self.ap.step(&inputs, DT);
            assert!(self
                .out
                .motors
                .throttle_norm
                .iter()
                .all(|m| m.is_finite() && (0.0..=1.0).contains(m)));
            let vz = self.veh.velocity_m_s.z;
            let airborne = self.veh.position_m.z > 0.0;
            self.veh.advance(&self.out.motors, DT);
            if airborne && self.veh.position_m.z <= 0.0 {
                self.worst_touchdown_m_s = self.worst_touchdown_m_s.max(-vz);
            }
            watch(&self.out, &self.veh);
        }
    }

    pub(super) fn fly(&mut self, secs: f32) {
        self.fly_with(secs, |_, _| {}, |_, _| {});
    }

    pub(super) fn horizontal_error_m(&self) -> f32 {
        hypotf(self.veh.position_m.x, self.veh.position_m.y)
    }

    pub(super) fn take_off(&mut self) {
        self.fly(0.2);
        assert_eq!(self.out.mode, FlightMode::Disarmed);
        self.veh.pilot.arm = true;
        self.fly(6.0);
        assert_eq!(self.out.mode, FlightMode::Hold, "{:?}", self.ap.events());
        assert!(
            (self.veh.position_m.z - 1.0).abs() < 0.1,
            "z {}",
            self.veh.position_m.z
        );
    }
}

#[test]
fn takes_off_holds_rejects_a_push_and_lands() {
    let mut f = Flight::new(config(), 1);
    f.take_off();
    f.fly(4.0);
    // Hold: RMS horizontal error over 5 s.
    let (mut sum, mut n) = (0.0f32, 0.0f32);
    f.fly_with(
        5.0,
        |_, _| {},
        |_, v| {
            sum += v.position_m.x * v.position_m.x + v.position_m.y * v.position_m.y;
            n += 1.0;
        },
    );
    let rms = libm::sqrtf(sum / n);
    std::println!("hold RMS {rms:.4} m");
    assert!(rms < 0.03, "RMS {rms}");
    // Seed 000's external force: 2 N for 1 s.
    f.veh.push_n.x = 2.0;
    let mut worst = 0.0f32;
    f.fly_with(
        1.0,
        |_, _| {},
        |_, v| worst = worst.max(hypotf(v.position_m.x, v.position_m.y)),
    );
    f.veh.push_n.x = 0.0;
    let mut back_after_s = None;
    let mut t = 0.0;
    f.fly_with(
        5.0,
        |_, _| {},
        |_, v| {
            t += DT;
            let err = hypotf(v.position_m.x, v.position_m.y);
            if err > 0.05 {
                back_after_s = None;
            } else if back_after_s.is_none() {
                back_after_s = Some(t);
            }
        },
    );
    std::println!("push: worst {worst:.3} m, back within 5 cm after {back_after_s:?} s");
    assert!(back_after_s.is_some_and(|s| s <= 3.0), "{back_after_s:?}");
    // Land.
    f.veh.pilot.arm = false;
    f.fly(6.0);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    assert_eq!(f.out.motors.throttle_norm, [0.0; 4]);
    assert!(
        f.veh.position_m.z == 0.0 && f.worst_touchdown_m_s < 0.8,
        "{}",
        f.worst_touchdown_m_s
    );
    assert!(f.horizontal_error_m() < 0.1);
    assert_eq!(f.out.failsafe, None);
}

#[test]
fn kill_switch_stops_the_motors_on_the_same_step() {
    let mut f = Flight::new(config(), 2);
    f.take_off();
    f.veh.pilot.kill = true;
    f.fly(0.002);
    assert_eq!(f.out.mode, FlightMode::Killed);
    assert_eq!(f.out.motors.throttle_norm, [0.0; 4]);
    // It stays stopped while falling, even with a bad dt on the way.
    let inputs = f.veh.sense(f.step, HZ);
    let out = f.ap.step(&inputs, f32::NAN);
    assert_eq!(out.motors.throttle_norm, [0.0; 4]);
    f.fly(1.0);
    assert_eq!(f.out.motors.throttle_norm, [0.0; 4]);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::KillSwitch));
}

#[test]
fn nan_inputs_are_counted_and_the_hold_survives_them() {
    let mut f = Flight::new(config(), 3);
    f.take_off();
    let mut k = 0u32;
    f.fly_with(
        1.0,
        |i, _| {
            k += 1;
            if k.is_multiple_of(10) {
                i.imu.gyro_rad_s[0] = f32::NAN;
                i.imu.accel_m_s2[2] = f32::INFINITY;
                i.pilot.roll_norm = f32::NAN;
                if let Some(b) = &mut i.battery {
                    b.voltage_v = f32::NAN;
                }
                if let Some(s) = &mut i.sonar {
                    s.range_m = f32::NAN;
                }
                if let Some(m) = &mut i.scan_match {
                    m.dx_m = f32::NAN;
                }
            }
        },
        |o, _| {
            assert!(o.estimate.position_m.iter().all(|v| v.is_finite()));
        },
    );
    f.fly(2.0);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert!(f.horizontal_error_m() < 0.1);
    let faults = f.ap.faults();
    assert!(
        faults.bad_pilot >= 49 && faults.bad_battery >= 49,
        "{faults:?}"
    );
    assert!(f.ap.estimator_counters().imu_faults >= 49);
    // A bad dt is a counted no-op.
    let before = f.ap.faults().bad_dt;
    let inputs = f.veh.sense(f.step, HZ);
    f.ap.step(&inputs, -1.0);
    assert_eq!(f.ap.faults().bad_dt, before + 1);
}

#[test]
fn lidar_failure_holds_on_the_imu_then_lands() {
    let mut f = Flight::new(config(), 4);
    f.take_off();
    f.veh.lidar_on = false;
    f.fly(1.8);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::LidarLost));
    // Nearly two seconds on the IMU alone: still near the hold point.
    assert!(f.horizontal_error_m() < 0.3, "{}", f.horizontal_error_m());
    f.fly(0.5);
    assert_eq!(f.out.mode, FlightMode::Land);
    f.fly(6.0);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    // The urgent descent is 1 m/s; the landing gear is good for 2.
    assert!(f.worst_touchdown_m_s < 1.3, "{}", f.worst_touchdown_m_s);
}

#[test]
fn low_battery_lands_and_critical_lands_faster() {
    let mut cfg = config();
    cfg.supervisor.takeoff_height_m = 2.0;
    let mut f = Flight::new(cfg, 5);
    f.veh.pilot.arm = true;
    f.fly(0.2);
    f.veh.pilot.arm = false;
    f.fly(0.1);
    f.veh.pilot.arm = true;
    f.fly(8.0);
    assert_eq!(f.out.mode, FlightMode::Hold);
    f.veh.battery_v = 10.3;
    f.fly(1.5);
    assert_eq!(
        (f.out.mode, f.out.failsafe),
        (FlightMode::Land, Some(FailsafeReason::BatteryLow))
    );
    f.fly(0.5);
    let slow = f.veh.velocity_m_s.z;
    f.veh.battery_v = 9.5;
    f.fly(1.5);
    assert_eq!(f.out.failsafe, Some(FailsafeReason::BatteryCritical));
    let fast = f.veh.velocity_m_s.z;
    assert!(fast < slow - 0.2, "{slow} {fast}");
    f.fly(4.0);
    // The touchdown shock is not in the test vehicle's accelerometer and the sonar is blind on
    // the floor: the floor constraint (at rest below height zero) ended the descent.
    assert!(f.ap.estimator_counters().at_rest.accepted > 0);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
}

#[test]
fn invalid_estimate_lands_level() {
    let mut cfg = config();
    cfg.estimator.ekf.max_position_std_m = 0.1;
    let mut f = Flight::new(cfg, 6);
    f.take_off();
    f.veh.lidar_on = false;
    let mut level_landing = true;
    f.fly_with(
        8.0,
        |_, _| {},
        |o, _| {
            if o.mode == FlightMode::Land {
                level_landing &= o.setpoint.is_some_and(|s| s.position_m[2] == 0.0);
            }
        },
    );
    assert!(level_landing);
    assert_eq!(f.out.mode, FlightMode::Disarmed);
    let reasons: std::vec::Vec<_> = f.ap.events().iter().map(|e| e.kind).collect();
    assert!(
        reasons.contains(&super::events::EventKind::Failsafe(
            FailsafeReason::EstimateInvalid
        )),
        "{reasons:?}"
    );
}

#[test]
fn manual_flight_is_rate_damped_and_follows_the_sticks() {
    let mut f = Flight::new(config(), 7);
    f.fly(0.2);
    f.veh.pilot.manual = true;
    f.veh.pilot.arm = true;
    f.veh.pilot.throttle_norm = 0.65;
    f.fly(1.0);
    assert_eq!(f.out.mode, FlightMode::Manual);
    assert!(f.veh.position_m.z > 0.2, "climbing: {}", f.veh.position_m.z);
    // Roll right for 0.2 s: positive roll about FLU x (right side down), and the rate dies out
    // after release.
    f.veh.pilot.roll_norm = 1.0;
    f.fly(0.2);
    let (roll, _, _) = f.veh.roll_pitch_yaw();
    assert!(roll > 0.05, "{roll}");
    f.veh.pilot.roll_norm = 0.0;
    f.fly(0.5);
    assert!(
        f.veh.rates_rad_s.norm() < 0.05,
        "{}",
        f.veh.rates_rad_s.norm()
    );
}

#[test]
fn autopilot_size_is_small_and_known() {
    let size = core::mem::size_of::<Autopilot>();
    std::println!("size_of::<Autopilot>() = {size} bytes");
    // About 4 KiB with the exploration mission's state (its config, the latest setpoint, the
    // companion frame's anchor and tallies: some 150 bytes), plus the MRAC's state (about
    // 1.4 kB), which is part of the cascade whichever controller flies; a bound, not a target.
    assert!(size <= 6656, "{size}");
}
