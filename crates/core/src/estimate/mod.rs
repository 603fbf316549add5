//! State estimation: tilt from gyro and accelerometer, and an EKF over position, velocity, yaw and
//! biases predicted with the IMU and corrected by the scan matcher and the sonar (seed 002
//! sec. IV: "EKF fusing laser, IMU and sonar"), by the drag the accelerometer feels, and by the companion computer's map pose. One
//! file per measurement model.

pub mod at_rest;
pub mod attitude;
pub mod drag;
pub mod ekf;
pub mod estimator;
mod frame;
pub mod imu;
pub mod pose_fix;
pub mod scan_match;
pub mod sonar;
pub mod validity;
