//! A small quadrotor for the autopilot's own tests (f32, Euler integration): rigid body, rotors
//! with two first-order lags as in seed 002, linear drag, a floor, ideal-ish sensors and a scan
//! matcher that reports the true pose change with noise. The simulator crate is the real
//! model; this one exists so the onboard code can be tested closed-loop inside `core`.

use crate::control::airframe::Airframe;
use crate::geom::Pose2;
use crate::msgs::{
    FrameKind, ImuSample, Inputs, MotorCommands, PilotInput, ScanMatchDelta, ScanMatchStatus,
    SonarSample, GRAVITY_M_S2,
};
use libm::hypotf;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Pelican-like: 1 kg, 0.21 m arms, 7 N per rotor at full command.
const MASS_KG: f32 = 1.0;
const ARM_M: f32 = 0.21;
const MAX_THRUST_N: f32 = 7.0;
const YAW_PER_THRUST_M: f32 = 0.016;
const INERTIA: [f32; 3] = [0.01, 0.01, 0.02];
const MOTOR_TAU_S: f32 = 0.0125;
const ROTOR_TAU_S: f32 = 0.025;
const DRAG_N_PER_M_S: f32 = 0.1;

/// This vehicle in the controllers' terms.
pub const AIRFRAME: Airframe = Airframe {
    frame: FrameKind::X,
    mass_kg: MASS_KG,
    inertia_kgm2: INERTIA,
    arm_length_m: ARM_M,
    max_thrust_n: MAX_THRUST_N,
    yaw_moment_per_thrust_m: YAW_PER_THRUST_M,
};

pub struct TestVehicle {
    pub position_m: Vector3<f32>,
    pub velocity_m_s: Vector3<f32>,
    pub attitude: UnitQuaternion<f32>,
    pub rates_rad_s: Vector3<f32>,
    motor_state: [f32; 4],
    rotor_speed: [f32; 4],
    /// External force (N, world), e.g. a push.
    pub push_n: Vector3<f32>,
    pub t_s: f64,
    rng: u64,
    reference: Pose2,
    has_reference: bool,
    /// The scan matcher's outputs can be switched off (lidar failure).
    pub lidar_on: bool,
    pub pilot: PilotInput,
    pub battery_v: f32,
}

impl TestVehicle {
    pub fn on_the_floor(seed: u64) -> Self {
        Self {
            position_m: Vector3::zeros(),
            velocity_m_s: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            rates_rad_s: Vector3::zeros(),
            motor_state: [0.0; 4],
            rotor_speed: [0.0; 4],
            push_n: Vector3::zeros(),
            t_s: 0.0,
            rng: seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1,
            reference: Pose2::IDENTITY,
            has_reference: false,
            lidar_on: true,
            pilot: PilotInput::default(),
            battery_v: 12.0,
        }
    }

    fn noise(&mut self, sigma: f32) -> f32 {
        // xorshift64*, sum of four uniforms: roughly normal, deterministic.
        let mut sum = 0.0;
        for _ in 0..4 {
            self.rng ^= self.rng >> 12;
            self.rng ^= self.rng << 25;
            self.rng ^= self.rng >> 27;
            let u =
                (self.rng.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
            sum += u - 0.5;
        }
        sigma * sum * libm::sqrtf(3.0)
    }

    pub fn roll_pitch_yaw(&self) -> (f32, f32, f32) {
        self.attitude.euler_angles()
    }

    /// Advances the body by `dt` under the given motor commands.
    pub fn advance(&mut self, motors: &MotorCommands, dt: f32) {
        let geometry = FrameKind::X.motors();
        let mut force_z = 0.0;
        let mut torque = Vector3::zeros();
        for (i, g) in geometry.iter().enumerate() {
            let cmd = motors.throttle_norm[i].clamp(0.0, 1.0);
            self.motor_state[i] += (cmd - self.motor_state[i]) * dt / MOTOR_TAU_S;
            self.rotor_speed[i] += (self.motor_state[i] - self.rotor_speed[i]) * dt / ROTOR_TAU_S;
            let thrust = MAX_THRUST_N * self.rotor_speed[i] * self.rotor_speed[i];
            let (x, y) = (g.arm_dir[0] * ARM_M, g.arm_dir[1] * ARM_M);
            force_z += thrust;
            let spin = if g.spins_ccw { -1.0 } else { 1.0 };
            torque += Vector3::new(y * thrust, -x * thrust, spin * YAW_PER_THRUST_M * thrust);
        }
        let inertia = Matrix3::from_diagonal(&Vector3::from(INERTIA));
        let w = self.rates_rad_s;
        let w_dot = inertia.try_inverse().unwrap_or_else(Matrix3::zeros)
            * (torque - w.cross(&(inertia * w)));
        self.rates_rad_s += w_dot * dt;
        self.attitude *= UnitQuaternion::from_scaled_axis(self.rates_rad_s * dt);
        let thrust_world = self.attitude * Vector3::new(0.0, 0.0, force_z);
        let accel = (thrust_world - self.velocity_m_s * DRAG_N_PER_M_S + self.push_n) / MASS_KG
            - Vector3::new(0.0, 0.0, GRAVITY_M_S2);
        self.velocity_m_s += accel * dt;
        self.position_m += self.velocity_m_s * dt;
        if self.position_m.z <= 0.0 {
            // The floor: no sinking, no sliding, no tipping.
            self.position_m.z = 0.0;
            self.velocity_m_s = Vector3::zeros();
            if force_z < MASS_KG * GRAVITY_M_S2 {
                let (_, _, yaw) = self.roll_pitch_yaw();
                self.attitude = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
                self.rates_rad_s = Vector3::zeros();
            }
        }
        self.t_s += dt as f64;
    }

    /// What the sensors report now: IMU every call, sonar at 20 Hz, scans at 5 Hz.
    pub fn sense(&mut self, step: u64, steps_per_s: u64) -> Inputs {
        let specific = if self.position_m.z <= 0.0 {
            // Resting on the floor: the floor pushes up with exactly gravity.
            self.attitude
                .inverse_transform_vector(&Vector3::new(0.0, 0.0, GRAVITY_M_S2))
        } else {
            // Thrust, drag and push over mass, in the body frame (gravity is not sensed).
            let force_z: f32 = self.rotor_speed.iter().map(|w| MAX_THRUST_N * w * w).sum();
            let external = (self.push_n - self.velocity_m_s * DRAG_N_PER_M_S) / MASS_KG;
            Vector3::new(0.0, 0.0, force_z / MASS_KG)
                + self.attitude.inverse_transform_vector(&external)
        };
        let imu = ImuSample {
            t_s: self.t_s,
            gyro_rad_s: [
                self.rates_rad_s.x + self.noise(0.003),
                self.rates_rad_s.y + self.noise(0.003),
                self.rates_rad_s.z + self.noise(0.003),
            ],
            accel_m_s2: [
                specific.x + self.noise(0.05),
                specific.y + self.noise(0.05),
                specific.z + self.noise(0.05),
            ],
        };
        let (roll, pitch, yaw) = self.roll_pitch_yaw();
        let sonar = (step.is_multiple_of(steps_per_s / 20)).then(|| SonarSample {
            t_s: self.t_s,
            range_m: self.position_m.z / (libm::cosf(roll) * libm::cosf(pitch)) + self.noise(0.01),
        });
        let scan_match = (self.lidar_on && step.is_multiple_of(steps_per_s / 5)).then(|| {
            // Matched against a keyframe (seed 000: the displacement from the reference scan),
            // replaced once the vehicle has moved 0.5 m from it.
            let now = Pose2::new(self.position_m.x, self.position_m.y, yaw);
            let d = self.reference.between(now);
            let status = if self.has_reference {
                ScanMatchStatus::Matched
            } else {
                ScanMatchStatus::ReferenceOnly
            };
            let becomes_reference = !self.has_reference || hypotf(d.x, d.y) > 0.5;
            if becomes_reference {
                self.reference = now;
            }
            self.has_reference = true;
            ScanMatchDelta {
                t_s: self.t_s,
                status,
                dx_m: d.x + self.noise(0.005),
                dy_m: d.y + self.noise(0.005),
                dtheta_rad: d.theta + self.noise(0.002),
                covariance: [[2.5e-5, 0.0, 0.0], [0.0, 2.5e-5, 0.0], [0.0, 0.0, 4e-6]],
                degenerate_axis: None,
                becomes_reference,
            }
        });
        Inputs {
            t_s: self.t_s,
            imu,
            sonar,
            scan_match,
            battery: Some(crate::msgs::BatterySample {
                t_s: self.t_s,
                voltage_v: self.battery_v,
            }),
            pilot: self.pilot,
            mission: None,
            companion: Default::default(),
            ground: Default::default(),
        }
    }
}
