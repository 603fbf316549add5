//! The reference model of one channel (seed 002 eq. 8): the response the vehicle should have,
//! with pseudo-control hedging taking out what the vehicle could not do.

use super::config::ReferenceConfig;

/// What one channel is asked to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Go to and hold this position (m).
    Position(f32),
    /// Follow a moving position (m) that moves at this velocity (m/s) and acceleration
    /// (m/s^2): both are fed forward so the model keeps up without lagging.
    Track {
        position_m: f32,
        velocity_m_s: f32,
        accel_m_s2: f32,
    },
    /// Fly this velocity (m/s); landing descends at a rate, not to a height.
    Velocity(f32),
    /// No control on this channel: level flight when the horizontal estimate is not trusted.
    Off,
}

/// Position and velocity of the reference model on one channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReferenceChannel {
    pub position_m: f32,
    pub velocity_m_s: f32,
}

impl ReferenceChannel {
    /// The model's acceleration `f_rm(x_rm, r)` before hedging (the feed-forward `nu_crm`):
    /// a velocity target from the position error, bounded, then an acceleration from the
    /// velocity error, bounded. Zero for [`Command::Off`].
    pub fn acceleration(&self, c: &ReferenceConfig, command: Command) -> f32 {
        let bounded = |v: f32| v.clamp(-c.max_speed_m_s, c.max_speed_m_s);
        let (target_m_s, feed_forward_m_s2) = match command {
            Command::Position(r) => (bounded(c.position_gain_per_s * (r - self.position_m)), 0.0),
            // As the PID's loops do: the bounded correction plus the feed-forwards.
            Command::Track {
                position_m,
                velocity_m_s,
                accel_m_s2,
            } => (
                bounded(c.position_gain_per_s * (position_m - self.position_m)) + velocity_m_s,
                accel_m_s2,
            ),
            Command::Velocity(v) => (bounded(v), 0.0),
            Command::Off => return 0.0,
        };
        (c.velocity_gain_per_s * (target_m_s - self.velocity_m_s) + feed_forward_m_s2)
            .clamp(-c.max_accel_m_s2, c.max_accel_m_s2)
    }

    /// Moves the model on by `dt` (s) at `accel_m_s2`, which is the model's own acceleration
    /// minus the hedge (semi-implicit Euler: the new velocity moves the position).
    pub fn advance(&mut self, accel_m_s2: f32, dt: f32) {
        self.velocity_m_s += accel_m_s2 * dt;
        self.position_m += self.velocity_m_s * dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> ReferenceConfig {
        ReferenceConfig {
            position_gain_per_s: 1.5,
            velocity_gain_per_s: 4.0,
            max_speed_m_s: 1.0,
            max_accel_m_s2: 4.0,
        }
    }

    /// A small step stays inside the bounds, so the model is the linear second-order system
    /// x'' = kv (kp (r - x) - x'), omega^2 = 6, 2 zeta omega = 4 (zeta = 0.816): its step
    /// response is known in closed form.
    #[test]
    fn small_step_follows_the_linear_second_order_response() {
        let c = config();
        let mut m = ReferenceChannel::default();
        let dt = 1e-4;
        let r = 0.1;
        let (wn, zeta) = (libm::sqrtf(6.0), 4.0 / (2.0 * libm::sqrtf(6.0)));
        let wd = wn * libm::sqrtf(1.0 - zeta * zeta);
        for k in 1..=30_000 {
            let a = m.acceleration(&c, Command::Position(r));
            m.advance(a, dt);
            let t = k as f32 * dt;
            let exact = r
                * (1.0
                    - libm::expf(-zeta * wn * t)
                        * (libm::cosf(wd * t) + zeta * wn / wd * libm::sinf(wd * t)));
            assert!(
                (m.position_m - exact).abs() < 2e-4,
                "t {t}: {m:?} vs {exact}"
            );
        }
        // 3 s is 5.5 time constants of the envelope: settled.
        assert!((m.position_m - r).abs() < 1e-3);
    }

    #[test]
    fn a_far_step_is_flown_at_the_speed_bound_and_a_rate_command_is_tracked() {
        let c = config();
        let mut m = ReferenceChannel::default();
        for _ in 0..2000 {
            let a = m.acceleration(&c, Command::Position(10.0));
            assert!(a.abs() <= c.max_accel_m_s2);
            m.advance(a, 0.001);
        }
        assert!((m.velocity_m_s - 1.0).abs() < 1e-3, "{m:?}");
        for _ in 0..2000 {
            let a = m.acceleration(&c, Command::Velocity(-0.5));
            m.advance(a, 0.001);
        }
        assert!((m.velocity_m_s + 0.5).abs() < 1e-3, "{m:?}");
        assert_eq!(m.acceleration(&c, Command::Off), 0.0);
        // A point moving at 0.8 m/s is followed without lag once the model has caught up.
        let mut m = ReferenceChannel::default();
        let mut r = 0.0;
        for _ in 0..5000 {
            let a = m.acceleration(
                &c,
                Command::Track {
                    position_m: r,
                    velocity_m_s: 0.8,
                    accel_m_s2: 0.0,
                },
            );
            m.advance(a, 0.001);
            r += 0.8 * 0.001;
        }
        assert!((m.position_m - r).abs() < 2e-3, "{m:?} {r}");
        // On a point that speeds up, the model's acceleration is the point's.
        let on_it = ReferenceChannel {
            position_m: 1.0,
            velocity_m_s: 0.5,
        };
        let a = on_it.acceleration(
            &c,
            Command::Track {
                position_m: 1.0,
                velocity_m_s: 0.5,
                accel_m_s2: 0.7,
            },
        );
        assert!((a - 0.7).abs() < 1e-6, "{a}");
    }

    #[test]
    fn a_hedge_equal_to_the_model_acceleration_stops_the_model() {
        let c = config();
        let mut m = ReferenceChannel::default();
        for _ in 0..100 {
            let a = m.acceleration(&c, Command::Position(1.0));
            // The vehicle achieved nothing: hedge = the whole command.
            m.advance(a - a, 0.01);
        }
        assert_eq!(m, ReferenceChannel::default());
    }
}
