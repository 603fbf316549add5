//! Scripted flight plans for the test pilot: take off, fly waypoints (turning to face each leg
//! first, like a ground robot, so scans look like the benchmark logs), land. The reference is a
//! pure function of time, so a plan is reproducible and can be sampled at any rate.

use crate::math::Vec3;
use crate::world::World;
use plumbline_core::geom::normalize_angle_f64;

/// `normalize_angle_f64(a)`, without its `remainder` (a libm call of some 130 instructions)
/// when |a| < 3π (a plan's yaw leaves that range only once its turns add up to more than a
/// full turn one way):
/// there the remainder's quotient is -1, 0 or 1 and a ∓ 2π is exact (Sterbenz: a and 2π within
/// a factor of two), so the result is bit for bit the same. The test pilot asks for the
/// reference at 250 Hz.
fn wrap_yaw(a: f64) -> f64 {
    use core::f64::consts::PI;
    if a > -PI && a <= PI {
        a
    } else if a > PI && a < 3.0 * PI {
        a - 2.0 * PI
    } else if a <= -PI && a > -3.0 * PI {
        a + 2.0 * PI
    } else {
        normalize_angle_f64(a)
    }
}

/// Where the vehicle should be at an instant, with the derivatives a tracking controller uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reference {
    pub position: Vec3,
    pub velocity: Vec3,
    pub acceleration: Vec3,
    pub yaw: f64,
    /// True once the plan has landed: motors may stop.
    pub finished: bool,
}

/// Speeds the plan is built with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanLimits {
    pub speed_mps: f64,
    pub climb_mps: f64,
    pub yaw_rate_radps: f64,
    /// Pause at each waypoint, s.
    pub dwell_s: f64,
}

impl Default for PlanLimits {
    fn default() -> Self {
        Self {
            speed_mps: 0.6,
            climb_mps: 0.5,
            yaw_rate_radps: 0.6,
            dwell_s: 0.5,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Leg {
    start_s: f64,
    duration_s: f64,
    from: Vec3,
    to: Vec3,
    from_yaw: f64,
    to_yaw: f64,
}

/// A sequence of smooth legs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    legs: Vec<Leg>,
}

/// Minimum-jerk progress s(u) = 10u³ - 15u⁴ + 6u⁵ and its first two derivatives in u.
fn min_jerk(u: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (
        10.0 * u3 - 15.0 * u3 * u + 6.0 * u3 * u2,
        30.0 * u2 - 60.0 * u3 + 30.0 * u2 * u2,
        60.0 * u - 180.0 * u2 + 120.0 * u3,
    )
}

/// Peak speed of a minimum-jerk move is 1.875 times the mean speed.
const MIN_JERK_PEAK: f64 = 1.875;

struct Builder {
    legs: Vec<Leg>,
    t: f64,
    at: Vec3,
    yaw: f64,
    limits: PlanLimits,
}

impl Builder {
    fn push(&mut self, to: Vec3, to_yaw: f64, duration_s: f64) {
        let to_yaw = self.yaw + normalize_angle_f64(to_yaw - self.yaw);
        self.legs.push(Leg {
            start_s: self.t,
            duration_s,
            from: self.at,
            to,
            from_yaw: self.yaw,
            to_yaw,
        });
        self.t += duration_s;
        self.at = to;
        self.yaw = to_yaw;
    }

    fn hold(&mut self, duration_s: f64) {
        self.push(self.at, self.yaw, duration_s);
    }

    fn climb_to(&mut self, z: f64) {
        let d = (z - self.at.z).abs();
        self.push(
            Vec3::new(self.at.x, self.at.y, z),
            self.yaw,
            (MIN_JERK_PEAK * d / self.limits.climb_mps).max(0.5),
        );
    }

    fn fly_to(&mut self, p: [f64; 2]) {
        let (dx, dy) = (p[0] - self.at.x, p[1] - self.at.y);
        let dist = dx.hypot(dy);
        if dist < 0.05 {
            return;
        }
        let heading = dy.atan2(dx);
        let turn = normalize_angle_f64(heading - self.yaw).abs();
        if turn > 0.02 {
            self.push(
                self.at,
                heading,
                MIN_JERK_PEAK * turn / self.limits.yaw_rate_radps,
            );
        }
        self.push(
            Vec3::new(p[0], p[1], self.at.z),
            heading,
            MIN_JERK_PEAK * dist / self.limits.speed_mps,
        );
        self.hold(self.limits.dwell_s);
    }

    fn land(mut self) -> Plan {
        self.hold(1.0);
        // Aim a little below the floor so the vehicle settles on it rather than hovering at 0.
        self.climb_to(-0.1);
        Plan { legs: self.legs }
    }
}

impl Plan {
    fn takeoff(world: &World, limits: PlanLimits) -> Builder {
        let mut b = Builder {
            legs: Vec::new(),
            t: 0.0,
            at: world.start_position(),
            yaw: world.start[2],
            limits,
        };
        b.hold(0.5);
        b.climb_to(world.altitude_m);
        b.hold(2.0);
        b
    }

    /// Take off at the world's start, fly its survey path, land at the last waypoint.
    pub fn survey(world: &World, limits: PlanLimits) -> Plan {
        let mut b = Self::takeoff(world, limits);
        for p in &world.path {
            b.fly_to(*p);
        }
        b.land()
    }

    /// Take off, hold over the start for `hold_s`, land.
    pub fn hold(world: &World, limits: PlanLimits, hold_s: f64) -> Plan {
        let mut b = Self::takeoff(world, limits);
        b.hold(hold_s.max(0.0));
        b.land()
    }

    /// Time at which the vehicle is back on the floor, s.
    pub fn duration_s(&self) -> f64 {
        self.legs.last().map_or(0.0, |l| l.start_s + l.duration_s)
    }

    /// The reference at `t_s` (the last point after the end).
    pub fn at(&self, t_s: f64) -> Reference {
        let i = self
            .legs
            .partition_point(|l| l.start_s <= t_s)
            .saturating_sub(1);
        let Some(leg) = self.legs.get(i) else {
            return Reference {
                finished: true,
                ..Reference::default()
            };
        };
        let u = (t_s - leg.start_s) / leg.duration_s;
        let (s, ds, dds) = min_jerk(u);
        let inv = 1.0 / leg.duration_s;
        let delta = leg.to - leg.from;
        let in_leg = u < 1.0;
        Reference {
            position: leg.from + delta * s,
            velocity: if in_leg {
                delta * (ds * inv)
            } else {
                Vec3::ZERO
            },
            acceleration: if in_leg {
                delta * (dds * inv * inv)
            } else {
                Vec3::ZERO
            },
            yaw: wrap_yaw(leg.from_yaw + (leg.to_yaw - leg.from_yaw) * s),
            finished: t_s >= self.duration_s(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn survey_visits_every_waypoint_within_the_speed_limit_and_lands() {
        let world = World::shipped("office").unwrap().unwrap();
        let limits = PlanLimits::default();
        let plan = Plan::survey(&world, limits);
        let end = plan.duration_s();
        let mut t = 0.0;
        let mut visited = vec![false; world.path.len()];
        let mut prev = plan.at(0.0);
        while t <= end + 1.0 {
            let r = plan.at(t);
            let h = r.velocity.x.hypot(r.velocity.y);
            assert!(h <= limits.speed_mps + 1e-9, "speed {h} at {t}");
            assert!(
                (r.position - prev.position).norm() < 0.01,
                "continuous at {t}"
            );
            for (k, p) in world.path.iter().enumerate() {
                if (r.position.x - p[0]).hypot(r.position.y - p[1]) < 1e-6
                    && (r.position.z - world.altitude_m).abs() < 1e-9
                {
                    visited[k] = true;
                }
            }
            prev = r;
            t += 0.01;
        }
        assert!(visited.iter().all(|&v| v), "{visited:?}");
        assert!(plan.at(end + 1.0).finished && plan.at(end + 1.0).position.z < 0.0);
    }

    /// Bit for bit, including both sides of the tie points ±π and ±3π.
    #[test]
    fn wrap_yaw_is_normalize_angle() {
        use core::f64::consts::PI;
        let mut a = -20.0;
        while a < 20.0 {
            assert_eq!(
                wrap_yaw(a).to_bits(),
                normalize_angle_f64(a).to_bits(),
                "{a}"
            );
            a += 0.0137;
        }
        let edges = [-3.0 * PI, -PI, 0.0, PI, 3.0 * PI];
        for a in edges
            .into_iter()
            .flat_map(|e| [e.next_down(), e, e.next_up(), -e])
        {
            assert_eq!(
                wrap_yaw(a).to_bits(),
                normalize_angle_f64(a).to_bits(),
                "{a}"
            );
        }
    }
}
