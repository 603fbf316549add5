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
//! - **vertical**: the mean vertical thrust differing from the weight (climb or sink over the
//!   window, vertical drag);
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
        let (sum, n) = items.fold((HoverExcess::default(), 0usize), |(s, n), e| {
            (s.plus(e), n + 1)
        });
        sum.times(1.0 / n.max(1) as f64)
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

    fn plus(&self, o: &Self) -> Self {
        let (a, b) = (self.fields(), o.fields());
        Self::from_fields(core::array::from_fn(|i| a[i] + b[i]))
    }

    fn times(&self, k: f64) -> Self {
        Self::from_fields(self.fields().map(|x| x * k))
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
