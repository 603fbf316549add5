//! External disturbances: Dryden-type turbulence and scheduled pushes (seed 000 sec. 4.3:
//! "external forces were applied to the quadcopter frame" to simulate drift; seed 002 sec. V.C
//! simulates gusts).

use crate::math::Vec3;
use crate::rng::Rng;

/// Turbulence: a mean wind plus, on each world axis, a first-order Gauss-Markov process with the
/// Dryden longitudinal spectrum Φ(ω) = σ² (2L/πV) / (1 + (Lω/V)²), i.e. correlation time L/V.
#[derive(Clone, Debug, PartialEq)]
pub struct GustParams {
    pub mean_wind_mps: Vec3,
    /// Standard deviation of the horizontal and vertical gust components, m/s.
    pub sigma_horizontal_mps: f64,
    pub sigma_vertical_mps: f64,
    /// Turbulence length scale L, m.
    pub length_scale_m: f64,
    /// Reference airspeed V that carries the eddies past the vehicle, m/s.
    pub airspeed_mps: f64,
}

impl GustParams {
    /// Indoor draughts: doors and ventilation, ±0.3 m/s horizontally, 2 m eddies at 1 m/s.
    pub fn indoor() -> Self {
        Self {
            mean_wind_mps: Vec3::ZERO,
            sigma_horizontal_mps: 0.3,
            sigma_vertical_mps: 0.1,
            length_scale_m: 2.0,
            airspeed_mps: 1.0,
        }
    }

    /// A gust storm, for testing a controller against more than the room's draughts: five
    /// times the indoor gusts' strength (±1.5 m/s horizontally, ±0.5 m/s vertically) and
    /// eddies four times as frequent (1 m at 2 m/s: a 0.5 s correlation time instead of 2 s).
    pub fn storm() -> Self {
        Self {
            mean_wind_mps: Vec3::ZERO,
            sigma_horizontal_mps: 1.5,
            sigma_vertical_mps: 0.5,
            length_scale_m: 1.0,
            airspeed_mps: 2.0,
        }
    }

    pub fn correlation_time_s(&self) -> f64 {
        self.length_scale_m / self.airspeed_mps
    }
}

/// The turbulence state, advanced in fixed updates.
#[derive(Clone, Debug)]
pub struct Gusts {
    params: GustParams,
    rng: Rng,
    gust: Vec3,
}

impl Gusts {
    pub fn new(params: GustParams, mut rng: Rng) -> Self {
        let s = [
            params.sigma_horizontal_mps,
            params.sigma_horizontal_mps,
            params.sigma_vertical_mps,
        ];
        // Start from the stationary distribution so there is no warm-up transient.
        let gust = Vec3::new(rng.gauss() * s[0], rng.gauss() * s[1], rng.gauss() * s[2]);
        Self { params, rng, gust }
    }

    /// Advances by `dt_s` (exact discretisation of the Gauss-Markov process).
    pub fn advance(&mut self, dt_s: f64) {
        let p = &self.params;
        let a = (-dt_s / p.correlation_time_s()).exp();
        let k = (1.0 - a * a).sqrt();
        let g = &mut self.gust;
        g.x = a * g.x + k * p.sigma_horizontal_mps * self.rng.gauss();
        g.y = a * g.y + k * p.sigma_horizontal_mps * self.rng.gauss();
        g.z = a * g.z + k * p.sigma_vertical_mps * self.rng.gauss();
    }

    /// Air velocity in the world frame, m/s.
    pub fn wind(&self) -> Vec3 {
        self.params.mean_wind_mps + self.gust
    }
}

/// A constant force applied to the frame for a while, world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Push {
    pub start_s: f64,
    pub duration_s: f64,
    pub force_n: Vec3,
}

/// Sum of the pushes active at `t_s`.
pub fn push_force(pushes: &[Push], t_s: f64) -> Vec3 {
    pushes
        .iter()
        .filter(|p| t_s >= p.start_s && t_s < p.start_s + p.duration_s)
        .fold(Vec3::ZERO, |f, p| f + p.force_n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gusts_have_the_dryden_variance_and_correlation_time() {
        for p in [GustParams::indoor(), GustParams::storm()] {
            check_dryden(p);
        }
    }

    fn check_dryden(p: GustParams) {
        let mut g = Gusts::new(p.clone(), Rng::new(5));
        let dt = 0.01;
        let lag = (p.correlation_time_s() / dt).round() as usize;
        let n = 400_000;
        let xs: Vec<f64> = (0..n)
            .map(|_| {
                g.advance(dt);
                g.wind().x
            })
            .collect();
        let var = xs.iter().map(|x| x * x).sum::<f64>() / n as f64;
        let cov = xs.iter().zip(&xs[lag..]).map(|(a, b)| a * b).sum::<f64>() / (n - lag) as f64;
        let s2 = p.sigma_horizontal_mps * p.sigma_horizontal_mps;
        assert!((var / s2 - 1.0).abs() < 0.1, "variance {var} vs {s2}");
        assert!(
            (cov / var - (-1f64).exp()).abs() < 0.05,
            "correlation at L/V {}",
            cov / var
        );
    }

    #[test]
    fn pushes_act_only_during_their_window() {
        let pushes = [Push {
            start_s: 1.0,
            duration_s: 0.5,
            force_n: Vec3::new(2.0, 0.0, 0.0),
        }];
        assert_eq!(push_force(&pushes, 0.9), Vec3::ZERO);
        assert_eq!(push_force(&pushes, 1.2).x, 2.0);
        assert_eq!(push_force(&pushes, 1.5), Vec3::ZERO);
    }
}
