//! The simulator's IMU and sonar logs as CSV: a header naming each column with its unit, then
//! one sample a line. Time is printed to the microsecond; readings in full (the shortest text
//! that reads back to the same `f32`).

use plumbline_core::msgs::{ImuSample, SonarSample};
use std::io::Write;

/// Column names of the IMU log.
pub const IMU_HEADER: &str =
    "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2";
/// Column names of the sonar log.
pub const SONAR_HEADER: &str = "t_s,range_m";

pub fn write_imu_header<W: Write + ?Sized>(w: &mut W) -> std::io::Result<()> {
    writeln!(w, "{IMU_HEADER}")
}

pub fn write_imu<W: Write + ?Sized>(w: &mut W, s: &ImuSample) -> std::io::Result<()> {
    let (g, a) = (s.gyro_rad_s, s.accel_m_s2);
    writeln!(
        w,
        "{:.6},{},{},{},{},{},{}",
        s.t_s, g[0], g[1], g[2], a[0], a[1], a[2]
    )
}

pub fn write_sonar_header<W: Write + ?Sized>(w: &mut W) -> std::io::Result<()> {
    writeln!(w, "{SONAR_HEADER}")
}

pub fn write_sonar<W: Write + ?Sized>(w: &mut W, s: &SonarSample) -> std::io::Result<()> {
    writeln!(w, "{:.6},{}", s.t_s, s.range_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_match_their_headers() {
        let mut out = Vec::new();
        write_imu_header(&mut out).unwrap();
        let imu = ImuSample {
            t_s: 1.5,
            gyro_rad_s: [0.1, -0.2, 0.0],
            accel_m_s2: [0.0, 0.0, 9.81],
        };
        write_imu(&mut out, &imu).unwrap();
        write_sonar_header(&mut out).unwrap();
        let sonar = SonarSample {
            t_s: 2.0,
            range_m: 0.75,
        };
        write_sonar(&mut out, &sonar).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[1], "1.500000,0.1,-0.2,0,0,0,9.81");
        assert_eq!(lines[3], "2.000000,0.75");
        assert_eq!(lines[0].split(',').count(), lines[1].split(',').count());
        assert_eq!(lines[2].split(',').count(), lines[3].split(',').count());
    }
}
