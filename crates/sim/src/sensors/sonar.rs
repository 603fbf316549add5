//! MaxBotix MB1040 (LV-MaxSonar-EZ4, seed 002's altimeter): 20 Hz, 6 in (0.1524 m) to 6.45 m,
//! 1 in (25.4 mm) resolution, a narrow cone. Mounted looking down body -z, so a tilted drone
//! measures the slant range; the cone is modelled by five rays (axis and four at the cone
//! half-angle) of which the nearest echo wins, as the first echo does on the real sensor.

use crate::math::Vec3;
use crate::rng::Rng;
use crate::world::scene::{Cylinder, Scene};
use plumbline_core::msgs::SonarSample;

#[derive(Clone, Debug, PartialEq)]
pub struct SonarParams {
    pub rate_hz: f64,
    pub min_range_m: f64,
    pub max_range_m: f64,
    pub resolution_m: f64,
    pub cone_half_angle_rad: f64,
    pub noise_m: f64,
}

impl SonarParams {
    pub fn mb1040() -> Self {
        Self {
            rate_hz: 20.0,
            min_range_m: 0.1524,
            max_range_m: 6.45,
            resolution_m: 0.0254,
            cone_half_angle_rad: 10f64.to_radians(),
            noise_m: 0.01,
        }
    }
}

/// A sonar in flight.
#[derive(Clone, Debug)]
pub struct Sonar {
    params: SonarParams,
    rng: Rng,
    next_s: f64,
}

impl Sonar {
    pub fn new(params: SonarParams, rng: Rng) -> Self {
        Self {
            params,
            rng,
            next_s: 0.0,
        }
    }

    /// A reading if one is due. `origin` is the transducer, `axes` the body x, y, z axes in the
    /// world frame. No echo within range reads as the maximum (the device's behaviour).
    ///
    /// The runner asks at every physics step (a reading is due at 20 Hz), so this is inlined
    /// there: see the runner's `lockstep` module on calls in the step loop.
    #[inline]
    pub fn sample(
        &mut self,
        t_s: f64,
        origin: Vec3,
        axes: [Vec3; 3],
        scene: &Scene,
        people: &[Cylinder],
    ) -> Option<SonarSample> {
        if t_s < self.next_s {
            return None;
        }
        let p = &self.params;
        self.next_s += 1.0 / p.rate_hz;
        let (s, c) = p.cone_half_angle_rad.sin_cos();
        let down = -axes[2];
        let rays = [
            down,
            down * c + axes[0] * s,
            down * c - axes[0] * s,
            down * c + axes[1] * s,
            down * c - axes[1] * s,
        ];
        let nearest = rays
            .iter()
            .filter_map(|d| scene.cast(origin, *d, p.max_range_m, people))
            .map(|h| h.range_m)
            .fold(p.max_range_m, f64::min);
        let noisy = nearest + p.noise_m * self.rng.gauss();
        let quantised = (noisy / p.resolution_m).round() * p.resolution_m;
        Some(SonarSample {
            t_s,
            range_m: quantised.clamp(p.min_range_m, p.max_range_m) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::World;

    fn scene() -> Scene {
        Scene::new(
            &World::parse("start 0 0 0\nceiling 3\noutline -10 -10 10 -10 10 10 -10 10\n").unwrap(),
        )
    }

    fn quiet_sonar_in_a_hall() -> (Sonar, Scene) {
        let params = SonarParams {
            noise_m: 0.0,
            ..SonarParams::mb1040()
        };
        (Sonar::new(params, Rng::new(1)), scene())
    }

    fn axes(roll: f64) -> [Vec3; 3] {
        let q = crate::math::Quat::from_euler(roll, 0.0, 0.0);
        [
            q.rotate(Vec3::new(1.0, 0.0, 0.0)),
            q.rotate(Vec3::new(0.0, 1.0, 0.0)),
            q.rotate(Vec3::Z),
        ]
    }

    #[test]
    fn reads_height_in_whole_inches_at_20_hz() {
        let (mut sonar, s) = quiet_sonar_in_a_hall();
        let samples: Vec<_> = (0..1000)
            .filter_map(|i| {
                sonar.sample(
                    i as f64 * 1e-3,
                    Vec3::new(0.0, 0.0, 1.0),
                    axes(0.0),
                    &s,
                    &[],
                )
            })
            .collect();
        assert_eq!(samples.len(), 20);
        let r = samples[0].range_m as f64;
        let inches = r / 0.0254;
        assert!(
            (inches - inches.round()).abs() < 1e-4 && (r - 1.0).abs() <= 0.0127 + 1e-6,
            "{r}"
        );
    }

    #[test]
    fn tilt_lengthens_the_reading_and_limits_clamp() {
        let (mut sonar, s) = quiet_sonar_in_a_hall();
        // Rolled 30 degrees at 1 m: the cone edge nearest vertical is 20 degrees off, 1/cos 20°.
        let r = sonar
            .sample(
                0.0,
                Vec3::new(0.0, 0.0, 1.0),
                axes(30f64.to_radians()),
                &s,
                &[],
            )
            .unwrap()
            .range_m as f64;
        assert!(
            (r - 1.0 / 20f64.to_radians().cos()).abs() <= 0.0127 + 1e-6,
            "{r}"
        );
        let low = sonar
            .sample(1.0, Vec3::new(0.0, 0.0, 0.05), axes(0.0), &s, &[])
            .unwrap();
        assert!(
            (low.range_m - 0.1524).abs() < 1e-6,
            "below the minimum reads the minimum"
        );
    }
}
