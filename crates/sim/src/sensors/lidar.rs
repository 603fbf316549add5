//! Scanning lidars: three device profiles, 3-D beams from the (possibly tilted) scan plane,
//! range noise, dropouts, grazing-angle misses and beams taken in sequence over the revolution.
//!
//! Beam k of a revolution is cast at `t0 + k * beam_dt` from the pose at that instant, so a
//! moving or turning drone produces the motion skew a real spinning lidar has.

use crate::math::Vec3;
use crate::rng::Rng;
use crate::world::nearby::Nearby;
use crate::world::scene::{Cylinder, Scene};

/// One device's geometry, timing and error model.
#[derive(Clone, Debug, PartialEq)]
pub struct LidarProfile {
    pub name: &'static str,
    pub beams: usize,
    /// Angle of the first beam, counter-clockwise from body x, rad.
    pub start_angle_rad: f64,
    /// Angle between beams (positive: counter-clockwise order), rad.
    pub increment_rad: f64,
    /// One revolution, s.
    pub period_s: f64,
    pub min_range_m: f64,
    pub max_range_m: f64,
    /// Range noise standard deviation: `noise_m + noise_fraction * range`.
    pub noise_m: f64,
    pub noise_fraction: f64,
    /// Probability that a beam with a target returns nothing (dust, dark surfaces).
    pub dropout: f64,
    /// Beams meeting a surface with cos(incidence) below this return nothing.
    pub min_cos_incidence: f64,
}

impl LidarProfile {
    /// Neato XV-11: 360 beams, one revolution in 250 ms, 4 m (seed 000 Table 1). Noisy (about
    /// 1 % of range) and prone to missing dark or grazing surfaces.
    pub fn xv11() -> Self {
        let inc = 1f64.to_radians();
        Self {
            name: "xv11",
            beams: 360,
            start_angle_rad: 0.0,
            increment_rad: inc,
            period_s: 0.25,
            min_range_m: 0.06,
            max_range_m: 4.0,
            noise_m: 0.005,
            noise_fraction: 0.01,
            dropout: 0.03,
            min_cos_incidence: 0.2,
        }
    }

    /// Hokuyo URG-04LX (seed 002): 240 degrees at 0.36 degrees, 10 Hz, 4 m, 1 mm resolution,
    /// ±10 mm below 1 m and 1 % beyond.
    pub fn urg04lx() -> Self {
        let inc = 0.36f64.to_radians();
        Self {
            name: "urg04lx",
            beams: 667,
            start_angle_rad: -120f64.to_radians(),
            increment_rad: inc,
            period_s: 0.1,
            min_range_m: 0.02,
            max_range_m: 4.0,
            noise_m: 0.0,
            noise_fraction: 0.01,
            dropout: 0.005,
            min_cos_incidence: 0.1,
        }
    }

    /// Hokuyo UTM-30LX (seed 000 Table 1): 270 degrees at 0.25 degrees (1,081 beams of the
    /// 1,440 per revolution), 25 ms per revolution, 30 m, ±30 mm.
    pub fn utm30lx() -> Self {
        let inc = 0.25f64.to_radians();
        Self {
            name: "utm30lx",
            beams: 1081,
            start_angle_rad: -135f64.to_radians(),
            increment_rad: inc,
            period_s: 0.025,
            min_range_m: 0.1,
            max_range_m: 30.0,
            noise_m: 0.01,
            noise_fraction: 0.0,
            dropout: 0.002,
            min_cos_incidence: 0.05,
        }
    }

    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "xv11" => Some(Self::xv11()),
            "urg04lx" => Some(Self::urg04lx()),
            "utm30lx" => Some(Self::utm30lx()),
            _ => None,
        }
    }

    /// Time between consecutive beams: the revolution period shared by a full turn.
    pub fn beam_dt_s(&self) -> f64 {
        self.period_s * self.increment_rad.abs() / core::f64::consts::TAU
    }
}

/// One completed revolution, equally spaced beams.
#[derive(Clone, Debug, PartialEq)]
pub struct LidarScan {
    /// Time of the first beam, s.
    pub stamp_s: f64,
    pub start_angle_rad: f64,
    pub increment_rad: f64,
    pub max_range_m: f64,
    /// Seconds between beams (beam k was taken at `stamp_s + k * beam_dt_s`).
    pub beam_dt_s: f64,
    pub ranges_m: Vec<f32>,
    pub valid: Vec<bool>,
}

/// Where the sensor is at the moment a beam is cast.
#[derive(Clone, Copy, Debug)]
pub struct SensorPose {
    pub origin: Vec3,
    /// Body axes in the world frame.
    pub x_axis: Vec3,
    pub y_axis: Vec3,
}

/// A lidar in flight: the profile, its random stream and the revolution being filled.
#[derive(Clone, Debug)]
pub struct Lidar {
    profile: LidarProfile,
    rng: Rng,
    beam_dt: f64,
    /// Per-beam direction cosines in the scan plane, precomputed.
    dirs: Vec<(f64, f64)>,
    next_beam: usize,
    rev_start_s: f64,
    scan: LidarScan,
    /// The walls within reach, kept between beams.
    nearby: Nearby,
}

impl Lidar {
    pub fn new(profile: LidarProfile, rng: Rng, first_stamp_s: f64) -> Self {
        let beam_dt = profile.beam_dt_s();
        let dirs = (0..profile.beams)
            .map(|k| (profile.start_angle_rad + profile.increment_rad * k as f64).sin_cos())
            .map(|(s, c)| (c, s))
            .collect();
        let scan = LidarScan {
            stamp_s: first_stamp_s,
            start_angle_rad: profile.start_angle_rad,
            increment_rad: profile.increment_rad,
            max_range_m: profile.max_range_m,
            beam_dt_s: beam_dt,
            ranges_m: Vec::with_capacity(profile.beams),
            valid: Vec::with_capacity(profile.beams),
        };
        let profile_reach = profile.max_range_m;
        Self {
            profile,
            rng,
            beam_dt,
            dirs,
            next_beam: 0,
            rev_start_s: first_stamp_s,
            scan,
            nearby: Nearby::new(profile_reach),
        }
    }

    pub fn profile(&self) -> &LidarProfile {
        &self.profile
    }

    /// True when the first beam of a new revolution is due at `t_s` (the runner records the
    /// true pose of the scan then).
    pub fn revolution_due(&self, t_s: f64) -> bool {
        self.next_beam == 0 && self.rev_start_s <= t_s
    }

    /// Casts every beam due at or before `t_s` from `pose`; returns the revolution when its
    /// last beam has been taken. Call once per physics step.
    #[inline]
    pub fn sample(
        &mut self,
        t_s: f64,
        pose: &SensorPose,
        scene: &Scene,
        people: &[Cylinder],
    ) -> Option<LidarScan> {
        let p = &self.profile;
        // `next_beam` through u32 (it is below `beams`, whose scan it indexes): SSE2 converts
        // only signed integers, so `usize as f64` takes five instructions, `u32 as f64` one.
        while self.next_beam < p.beams
            && self.rev_start_s + self.next_beam as u32 as f64 * self.beam_dt <= t_s
        {
            let (c, s) = self.dirs[self.next_beam];
            let dir = pose.x_axis * c + pose.y_axis * s;
            let reading = self
                .nearby
                .cast(scene, pose.origin, dir, p.max_range_m, people)
                .and_then(|hit| {
                    let lost = hit.range_m < p.min_range_m
                        || hit.cos_incidence < p.min_cos_incidence
                        || self.rng.chance(p.dropout);
                    let sigma = p.noise_m + p.noise_fraction * hit.range_m;
                    let r = hit.range_m + sigma * self.rng.gauss();
                    (!lost && r > p.min_range_m && r < p.max_range_m).then_some(r)
                });
            self.scan.ranges_m.push(reading.unwrap_or(0.0) as f32);
            self.scan.valid.push(reading.is_some());
            self.next_beam += 1;
        }
        if self.next_beam < p.beams {
            return None;
        }
        self.rev_start_s += p.period_s;
        self.next_beam = 0;
        let mut next = self.scan.clone();
        next.stamp_s = self.rev_start_s;
        next.ranges_m.clear();
        next.valid.clear();
        Some(core::mem::replace(&mut self.scan, next))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::World;

    fn level_pose(x: f64, y: f64) -> SensorPose {
        SensorPose {
            origin: Vec3::new(x, y, 1.0),
            x_axis: Vec3::new(1.0, 0.0, 0.0),
            y_axis: Vec3::new(0.0, 1.0, 0.0),
        }
    }

    fn run_revolution(
        lidar: &mut Lidar,
        scene: &Scene,
        pose_at: impl Fn(f64) -> SensorPose,
    ) -> LidarScan {
        let mut t = 0.0;
        loop {
            t += 1e-3;
            if let Some(scan) = lidar.sample(t, &pose_at(t), scene, &[]) {
                return scan;
            }
        }
    }

    #[test]
    fn noise_statistics_match_the_profile() {
        // A 3 m circle of walls around the sensor: every beam's true range is ~3 m.
        let n = 720;
        let pts: Vec<String> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * core::f64::consts::TAU;
                format!("{} {}", 3.0 * a.cos(), 3.0 * a.sin())
            })
            .collect();
        let w = World::parse(&format!(
            "start 0 0 0\nceiling 3\noutline {}\n",
            pts.join(" ")
        ))
        .unwrap();
        let scene = Scene::new(&w);
        let profile = LidarProfile {
            dropout: 0.1,
            ..LidarProfile::utm30lx()
        };
        let mut lidar = Lidar::new(profile.clone(), Rng::new(3), 0.0);
        let (mut n_ok, mut n_all, mut sum, mut sum2) = (0usize, 0usize, 0.0, 0.0);
        let true_range = |k: usize| {
            // The polygon's edge midpoints are at 3 cos(pi / n); beams vary between that and 3.
            let a = profile.start_angle_rad + profile.increment_rad * k as f64;
            let step = core::f64::consts::TAU / n as f64;
            let local = a.rem_euclid(step) - step / 2.0;
            3.0 * (step / 2.0).cos() / local.cos()
        };
        for _ in 0..40 {
            let scan = run_revolution(&mut lidar, &scene, |_| level_pose(0.0, 0.0));
            for (k, (&r, &ok)) in scan.ranges_m.iter().zip(&scan.valid).enumerate() {
                n_all += 1;
                if ok {
                    n_ok += 1;
                    let e = r as f64 - true_range(k);
                    sum += e;
                    sum2 += e * e;
                }
            }
        }
        let (mean, std) = (sum / n_ok as f64, (sum2 / n_ok as f64).sqrt());
        let drop = 1.0 - n_ok as f64 / n_all as f64;
        assert!(mean.abs() < 0.001, "bias {mean}");
        assert!((std - 0.01).abs() < 0.0005, "std {std}");
        assert!((drop - 0.1).abs() < 0.01, "dropout {drop}");
    }

    #[test]
    fn beams_are_taken_in_sequence_so_motion_skews_the_scan() {
        let w = World::parse("start 0 0 0\noutline -2.5 -2.5 2.5 -2.5 2.5 2.5 -2.5 2.5\n").unwrap();
        let scene = Scene::new(&w);
        let quiet = LidarProfile {
            noise_m: 0.0,
            noise_fraction: 0.0,
            dropout: 0.0,
            ..LidarProfile::xv11()
        };
        // Moving at 1 m/s along +x during the 250 ms revolution.
        let mut lidar = Lidar::new(quiet.clone(), Rng::new(1), 0.0);
        let scan = run_revolution(&mut lidar, &scene, |t| level_pose(t, 0.0));
        assert_eq!(scan.ranges_m.len(), 360);
        assert!(scan.valid.iter().all(|&v| v));
        // Beam 0 (ahead, t = 0) sees the wall 2.5 m away; beam 180 (behind) is taken half a
        // revolution later, 0.125 m further along, so it reads 2.625 m.
        assert!(
            (scan.ranges_m[0] - 2.5).abs() < 2e-3,
            "{}",
            scan.ranges_m[0]
        );
        assert!(
            (scan.ranges_m[180] - 2.625).abs() < 2e-3,
            "{}",
            scan.ranges_m[180]
        );
        let next = run_revolution(&mut lidar, &scene, |t| level_pose(t, 0.0));
        assert!(
            (next.stamp_s - 0.25).abs() < 1e-12,
            "revolutions follow each other"
        );
    }

    #[test]
    fn targets_beyond_max_range_are_invalid_not_max() {
        let w = World::parse("start 0 0 0\noutline -3 -3 30 -3 30 3 -3 3\n").unwrap();
        let scene = Scene::new(&w);
        let mut lidar = Lidar::new(LidarProfile::xv11(), Rng::new(1), 0.0);
        let scan = run_revolution(&mut lidar, &scene, |_| level_pose(0.0, 0.0));
        assert!(
            !scan.valid[0],
            "the far wall at 30 m is beyond the XV-11's 4 m"
        );
        assert_eq!(scan.ranges_m[0], 0.0);
        assert!(scan.valid[90], "the side wall at 3 m is seen");
    }
}
