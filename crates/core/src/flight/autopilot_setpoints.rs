//! What each flying mode asks of the cascade: the hold point, the companion's mission target
//! (checked against the latest revolution, [`crate::flight::setpoint_guard`]), or a landing
//! that holds only the axes the estimate still knows.

use super::Autopilot;
use crate::control::cascade::{CascadeSetpoint, FeedForward, Vertical};
use crate::estimate::validity::Horizontal;
use crate::flight::setpoint_guard::{guard_target, Loops};
use crate::msgs::{EstimatedState, FailsafeReason, FlightMode, MissionSetpoint, PositionSetpoint};

impl Autopilot {
    /// A mission setpoint, in Hold, becomes the hold point (so the vehicle stays where the
    /// mission left it when the setpoints stop); returns its velocity and acceleration to feed
    /// forward. Other modes ignore the mission: takeoff, landing and failsafes keep their own
    /// setpoints. A setpoint with a non-finite value is ignored whole.
    pub(super) fn follow(
        &mut self,
        mode: FlightMode,
        mission: Option<MissionSetpoint>,
    ) -> Option<FeedForward> {
        let m = mission.filter(|_| mode == FlightMode::Hold)?;
        let finite = m
            .position_m
            .iter()
            .chain(&m.velocity_m_s)
            .chain(&m.acceleration_m_s2)
            .all(|v| v.is_finite())
            && m.yaw_rad.is_finite();
        if !finite {
            self.faults.bad_mission = self.faults.bad_mission.saturating_add(1);
            return None;
        }
        self.home = PositionSetpoint {
            position_m: m.position_m,
            yaw_rad: m.yaw_rad,
        };
        Some(FeedForward {
            velocity_m_s: m.velocity_m_s,
            accel_m_s2: m.acceleration_m_s2,
        })
    }

    /// The cascade setpoint of each flying mode.
    pub(super) fn guide(
        &mut self,
        mode: FlightMode,
        failsafe: Option<FailsafeReason>,
        e: &EstimatedState,
        t_s: f64,
    ) -> Option<CascadeSetpoint> {
        let hold_xy = [self.home.position_m[0], self.home.position_m[1]];
        let yaw_rad = self.home.yaw_rad;
        match mode {
            FlightMode::Takeoff | FlightMode::Hold => Some(CascadeSetpoint {
                horizontal_m: Some(hold_xy),
                feed_forward: None,
                vertical: Vertical::Height(self.home.position_m[2]),
                yaw_rad,
            }),
            FlightMode::Explore | FlightMode::Return => {
                // Lidar lost: the companion's setpoints are not chased on the IMU alone; the
                // mission holds, as the hold mode would, until the failsafe lands or clears.
                let lidar_lost = failsafe == Some(FailsafeReason::LidarLost);
                let frame = *self.estimator.companion_frame();
                let loop_xy = self.config.cascade.position_xy;
                let [x, y, yaw_rad] = self.mission.target(t_s, &frame, e, loop_xy.kp, lidar_lost);
                let mut target = [x, y];
                let limit = self.config.mission.guard;
                let velocity_kp = self.config.cascade.velocity_xy.kp;
                let loops = Loops {
                    gain_1_s: loop_xy.kp,
                    max_speed_m_s: loop_xy.output_limit,
                    response_s: if velocity_kp > 0.0 {
                        1.0 / velocity_kp
                    } else {
                        0.0
                    },
                };
                let guarded = self
                    .nearest_hits
                    .as_ref()
                    .and_then(|hits| guard_target(target, e, hits, &limit, &loops));
                if let Some(g) = guarded {
                    self.mission.count_guarded();
                    target = g;
                }
                Some(CascadeSetpoint {
                    horizontal_m: Some(target),
                    feed_forward: None,
                    vertical: Vertical::Height(self.home.position_m[2]),
                    yaw_rad,
                })
            }
            FlightMode::Land => {
                let c = &self.config.landing;
                let urgent = matches!(
                    failsafe,
                    Some(FailsafeReason::BatteryCritical | FailsafeReason::LidarLost)
                );
                let rate = if urgent {
                    c.urgent_descent_m_s
                } else {
                    c.descent_m_s
                };
                // After the lidar is lost the IMU-only estimate drifts faster than its
                // covariance admits (biases and tilt are no longer observed): land level, also
                // when the estimate went invalid first and named the failsafe.
                let lidar_lost = failsafe == Some(FailsafeReason::LidarLost)
                    || self.supervisor.lidar_silent(t_s);
                let horizontal = if lidar_lost {
                    Horizontal::Unknown
                } else {
                    self.estimator.horizontal()
                };
                Some(CascadeSetpoint {
                    horizontal_m: landing_point(horizontal, hold_xy, e),
                    feed_forward: None,
                    vertical: Vertical::ClimbRate(-rate),
                    yaw_rad,
                })
            }
            FlightMode::Disarmed | FlightMode::Killed | FlightMode::Manual => None,
        }
    }
}

/// Where a landing holds horizontally: the hold point with both axes known, nothing (a level
/// landing) with neither. Known across one axis only (a corridor), the hold point's offset is
/// kept across it and dropped along it: across, the position is held; along, the position loop
/// sees no error, so the velocity loop stops the vehicle on the velocity estimate, which knows
/// more than a level landing, which keeps whatever speed the vehicle had (drag takes some ten
/// seconds to halve it).
fn landing_point(
    horizontal: Horizontal,
    hold_xy: [f32; 2],
    e: &EstimatedState,
) -> Option<[f32; 2]> {
    let here = [e.position_m[0], e.position_m[1]];
    match horizontal {
        Horizontal::Known => Some(hold_xy),
        Horizontal::Across(a) => {
            let [ax, ay] = a.across_axis;
            let offset = ax * (hold_xy[0] - here[0]) + ay * (hold_xy[1] - here[1]);
            Some([here[0] + offset * ax, here[1] + offset * ay])
        }
        Horizontal::Unknown => None,
    }
}
