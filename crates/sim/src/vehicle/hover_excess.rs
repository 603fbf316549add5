//! How far a flight's mean power lies above its body's still hover ([`StillHover`]), and why:
//! the largest saving any control could make over the same hold. The excess is measured from the
//! energy integrated at every physics step and split, from the sampled rotor speeds, thrust and
//! attitude, into terms that telescope to it:
//!
//! - **spin-up**: the power that accelerates the rotors (I_r Ω Ω̇), net of what slowing returns;
//! - **differential**: the rotors not sharing the thrust in the still-hover ratio (the moments
//!   attitude control asks for): power above the balanced split at the same total thrust;
//! - **fluctuation**: the total thrust varying about its mean; power is convex in it (∝ T^{3/2}),
//!   so to second order this is 3/8 · Var(T)/T̄² of the collective power;
//! - **tilt**: the thrust along body z exceeding its vertical part, T̄ against mean(T cos θ);
//! - **vertical**: the mean vertical thrust differing from the weight (vertical gusts dragging
//!   on the vehicle, climb or sink over the window);
//! - **sampling**: the energy-integrated mean against the mean of the samples (what the 50 Hz
//!   samples miss of the 1 kHz power).

use crate::runner::StateSample;
use crate::vehicle::power::power;
use crate::vehicle::still_hover::StillHover;
use crate::vehicle::VehicleParams;

/// A flight window's mean power above its still hover, and its parts, all in W of total
/// electrical power (motors, ESCs and avionics).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HoverExcess {
    /// The still hover's power, W.
    pub floor_w: f64,
    /// Mean power over the window from the integrated energy, minus the floor.
    pub measured_w: f64,
    pub spin_up_w: f64,
    pub differential_w: f64,
    pub fluctuation_w: f64,
    pub tilt_w: f64,
    pub vertical_w: f64,
    pub sampling_w: f64,
    /// The excess the second-order model predicts from the sampled rotor states, with no
    /// integrated energy: spin-up and differential as above, plus the still hover's
    /// thrust-dependent power times 3/8 Var(T)/W² (fluctuation), 3/2 (mean(1/cos θ) - 1)
    /// (tilt) and 3/2 (mean(T cos θ)/W - 1) (vertical). Its gap to `measured_w` is the
    /// expansion's higher orders plus the sampling.
    pub predicted_w: f64,
}

impl HoverExcess {
    /// The parts, in the order the module lists them, with their names.
    pub fn parts(&self) -> [(&'static str, f64); 6] {
        [
            ("spin_up", self.spin_up_w),
            ("differential", self.differential_w),
            ("fluctuation", self.fluctuation_w),
            ("tilt", self.tilt_w),
            ("vertical", self.vertical_w),
            ("sampling", self.sampling_w),
        ]
    }

    /// The excess as a fraction of the floor.
    pub fn measured_fraction(&self) -> f64 {
        self.measured_w / self.floor_w
    }

    /// Each field the mean of `items`' (for several seeds of one setting).
    pub fn mean<'a>(items: impl Iterator<Item = &'a HoverExcess>) -> HoverExcess {
        let (sum, n) = items.fold(([0.0; 9], 0usize), |(s, n), e| {
            let f = e.fields();
            (core::array::from_fn(|i| s[i] + f[i]), n + 1)
        });
        Self::from_fields(sum.map(|x| x / n.max(1) as f64))
    }

    fn fields(&self) -> [f64; 9] {
        [
            self.floor_w,
            self.measured_w,
            self.spin_up_w,
            self.differential_w,
            self.fluctuation_w,
            self.tilt_w,
            self.vertical_w,
            self.sampling_w,
            self.predicted_w,
        ]
    }

    fn from_fields(f: [f64; 9]) -> Self {
        let [floor_w, measured_w, spin_up_w, differential_w, fluctuation_w, tilt_w, vertical_w, sampling_w, predicted_w] =
            f;
        Self {
            floor_w,
            measured_w,
            spin_up_w,
            differential_w,
            fluctuation_w,
            tilt_w,
            vertical_w,
            sampling_w,
            predicted_w,
        }
    }
}

/// The excess of the window `samples` (consecutive state samples of one flight, at least two)
/// over `floor`, for vehicle `p`'s power model. Each sample stands for the interval since the
/// one before it, so the first only opens the window. `None` for fewer than two samples.
pub fn hover_excess(
    p: &VehicleParams,
    floor: &StillHover,
    samples: &[StateSample],
) -> Option<HoverExcess> {
    let (first, last) = (samples.first()?, samples.last()?);
    let body = samples.get(1..).filter(|s| !s.is_empty())?;
    let n = body.len() as f64;
    let mean = |f: &dyn Fn(&StateSample) -> f64| body.iter().map(f).sum::<f64>() / n;
    let cos_tilt = |s: &StateSample| s.euler[0].cos() * s.euler[1].cos();
    let steady = |s: &StateSample| power(p, &s.rotor_speed, &[0.0; 4]).total_w();
    let at = |thrust_n: f64| floor.total_w_at(p, thrust_n);
    let floor_w = floor.power.total_w();

    let measured_w = (last.energy_wh - first.energy_wh) * 3600.0 / (last.t_s - first.t_s) - floor_w;
    let thrust = mean(&|s| s.thrust_n);
    let vertical_thrust = mean(&|s| s.thrust_n * cos_tilt(s));
    let thrust_var = mean(&|s| (s.thrust_n - thrust).powi(2));
    let spin_up_w = mean(&|s| s.power_w - steady(s));
    let differential_w = mean(&|s| steady(s) - at(s.thrust_n));
    let fluctuation_w = mean(&|s| at(s.thrust_n)) - at(thrust);
    let tilt_w = at(thrust) - at(vertical_thrust);
    let vertical_w = at(vertical_thrust) - floor_w;
    let sampled = spin_up_w + differential_w + fluctuation_w + tilt_w + vertical_w;

    // d(total power)/d(thrust/weight) at the floor: 3/2 of the motors' and ESCs' share.
    let collective_w = floor.power.motors_w * (1.0 + p.esc_loss_fraction);
    let w = floor.weight_n;
    let predicted_w = spin_up_w
        + differential_w
        + collective_w
            * (0.375 * thrust_var / (w * w)
                + 1.5 * (mean(&|s| 1.0 / cos_tilt(s)) - 1.0)
                + 1.5 * (vertical_thrust / w - 1.0));
    Some(HoverExcess {
        floor_w,
        measured_w,
        spin_up_w,
        differential_w,
        fluctuation_w,
        tilt_w,
        vertical_w,
        sampling_w: measured_w - sampled,
        predicted_w,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::vehicle::dynamics::Dynamics;

    /// Samples at 50 Hz of a body whose rotors all run at `scale(t)` times the still hover's
    /// speeds, rolled by `roll(t)`, with the energy integrated from the sampled power.
    fn flight(
        p: &VehicleParams,
        floor: &StillHover,
        scale: impl Fn(f64) -> f64,
        roll: impl Fn(f64) -> f64,
    ) -> Vec<StateSample> {
        let mut energy_wh = 0.0;
        (0..=3000)
            .map(|k| {
                let t_s = k as f64 * 0.02;
                let rotor_speed = floor.rotor_speed.map(|w| w * scale(t_s));
                let power_w = power(p, &rotor_speed, &[0.0; 4]).total_w();
                if k > 0 {
                    energy_wh += power_w * 0.02 / 3600.0;
                }
                StateSample {
                    t_s,
                    position: Vec3::ZERO,
                    reference: None,
                    euler: [roll(t_s), 0.0, 0.0],
                    battery_v: 12.0,
                    power_w,
                    energy_wh,
                    rotor_speed,
                    thrust_n: floor.weight_n * scale(t_s).powi(2),
                }
            })
            .collect()
    }

    fn floor_of(p: &VehicleParams) -> StillHover {
        StillHover::of(p, &Dynamics::new(p, [1.02, 0.99, 1.0, 1.01], 1e-3)).unwrap()
    }

    #[test]
    fn a_still_hover_has_no_excess() {
        let p = VehicleParams::f450();
        let floor = floor_of(&p);
        let x = hover_excess(&p, &floor, &flight(&p, &floor, |_| 1.0, |_| 0.0)).unwrap();
        assert!(
            x.measured_w.abs() < 1e-9 && x.predicted_w.abs() < 1e-9,
            "{x:?}"
        );
        assert!(x.parts().iter().all(|(_, w)| w.abs() < 1e-9), "{x:?}");
    }

    #[test]
    fn thrust_fluctuation_costs_three_eighths_of_its_relative_variance() {
        let p = VehicleParams::f450();
        let floor = floor_of(&p);
        // Thrust W (1 + a sin(2π t / 0.7 s)): variance a²/2 of W².
        let a = 0.1_f64;
        let wave = |t: f64| (1.0 + a * (core::f64::consts::TAU * t / 0.7).sin()).sqrt();
        let x = hover_excess(&p, &floor, &flight(&p, &floor, wave, |_| 0.0)).unwrap();
        let collective = floor.power.motors_w * (1.0 + p.esc_loss_fraction);
        let expected = collective * 0.375 * a * a / 2.0;
        assert!(
            (x.fluctuation_w - expected).abs() < 0.03 * expected,
            "{x:?}"
        );
        assert!(x.sampling_w.abs() < 1e-9, "{x:?}");
        assert!(
            (x.predicted_w - x.measured_w).abs() < 0.03 * x.measured_w,
            "{x:?}"
        );
        assert!(
            x.tilt_w.abs() < 1e-9 && x.differential_w.abs() < 1e-9,
            "{x:?}"
        );
    }

    #[test]
    fn a_steady_tilt_costs_the_thrust_that_holds_the_weight_up() {
        let p = VehicleParams::f450();
        let floor = floor_of(&p);
        // Rolled 0.2 rad with the thrust raised by 1/cos: the vertical part carries the weight.
        let roll = 0.2_f64;
        let scale = |_| (1.0 / roll.cos()).sqrt();
        let x = hover_excess(&p, &floor, &flight(&p, &floor, scale, |_| roll)).unwrap();
        let expected = floor.total_w_at(&p, floor.weight_n / roll.cos()) - floor.power.total_w();
        assert!((x.tilt_w - expected).abs() < 1e-9 * expected, "{x:?}");
        assert!((x.measured_w - expected).abs() < 1e-6 * expected, "{x:?}");
        assert!(
            x.vertical_w.abs() < 1e-9 && x.fluctuation_w.abs() < 1e-9,
            "{x:?}"
        );
        // Second order: 3/2 (1/cos - 1) is within a few percent at 0.2 rad.
        assert!((x.predicted_w - expected).abs() < 0.05 * expected, "{x:?}");
    }

    #[test]
    fn fewer_than_two_samples_give_nothing() {
        let p = VehicleParams::f450();
        let floor = floor_of(&p);
        let one = flight(&p, &floor, |_| 1.0, |_| 0.0);
        assert_eq!(hover_excess(&p, &floor, &one[..1]), None);
        assert_eq!(hover_excess(&p, &floor, &[]), None);
    }
}
