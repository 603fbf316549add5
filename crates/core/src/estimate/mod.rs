//! State estimation: tilt from gyro and accelerometer, and an EKF over position, velocity, yaw and
//! biases predicted with the IMU and corrected by the scan matcher and the sonar (seed 002
//! sec. IV: "EKF fusing laser, IMU and sonar"), and by the drag the accelerometer feels. One
//! file per measurement model.

pub mod at_rest;
pub mod attitude;
pub mod drag;
pub mod ekf;
pub mod estimator;
pub mod imu;
pub mod scan_match;
pub mod sonar;
