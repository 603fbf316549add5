//! The adaptive element (seed 002 eq. 11, `nu_ad = W^T sigma(x)`): Gaussian radial basis
//! functions plus a bias and linear terms, one weight vector per channel, trained by eq. 12 with
//! e-modification and kept inside a ball by projection.
//!
//! The bias makes the element an integrator when nothing else explains the error (seed 002:
//! "the output of the adaptive element can be replaced by an integrator"); the linear terms
//! carry errors proportional to speed or commanded acceleration (a thrust scale error shows as
//! a fraction of the commanded acceleration); the Gaussians carry what is neither.

use libm::{expf, sqrtf};

/// Inputs to the network: world velocity (3) over the velocity scale, then the reference
/// model's acceleration (3) over the acceleration scale. Both are exogenous to this step's
/// pseudo-control, so the network's output never feeds back into its own input.
pub const INPUTS: usize = 6;

/// Normalised inputs are clamped to this magnitude, so a wild estimate cannot drive the
/// linear terms far outside the range the centres cover.
const INPUT_CLAMP: f32 = 1.5;

/// The basis `sigma(x)` for one input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis<const C: usize> {
    /// The normalised inputs (the linear terms); the bias term is 1 and is not stored.
    pub linear: [f32; INPUTS],
    /// The Gaussians' outputs, in (0, 1].
    pub rbf: [f32; C],
}

impl<const C: usize> Basis<C> {
    /// Normalises `velocity_m_s` and `accel_m_s2` and evaluates the Gaussians of `network`.
    pub fn new(
        network: &RbfNetwork<C>,
        velocity_m_s: [f32; 3],
        accel_m_s2: [f32; 3],
        velocity_scale_m_s: f32,
        accel_scale_m_s2: f32,
        width: f32,
    ) -> Self {
        let mut linear = [0.0; INPUTS];
        for k in 0..3 {
            linear[k] = (velocity_m_s[k] / velocity_scale_m_s).clamp(-INPUT_CLAMP, INPUT_CLAMP);
            linear[3 + k] = (accel_m_s2[k] / accel_scale_m_s2).clamp(-INPUT_CLAMP, INPUT_CLAMP);
        }
        let scale = -0.5 / (width * width);
        let rbf = core::array::from_fn(|i| {
            let d2: f32 = network.centres[i]
                .iter()
                .zip(&linear)
                .map(|(c, x)| (c - x) * (c - x))
                .sum();
            expf(scale * d2)
        });
        Self { linear, rbf }
    }
}

/// The network's weights for three channels (world x, y, z) and its `C` centres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RbfNetwork<const C: usize> {
    /// Centres in normalised input space, spread over [-1, 1]^6 by a Halton sequence, which
    /// covers the cube evenly for any `C` without a random seed.
    centres: [[f32; INPUTS]; C],
    bias: [f32; 3],
    linear: [[f32; 3]; INPUTS],
    rbf: [[f32; 3]; C],
}

impl<const C: usize> Default for RbfNetwork<C> {
    fn default() -> Self {
        Self::new()
    }
}

/// The first six primes: one Halton base per input.
const HALTON_BASES: [u32; INPUTS] = [2, 3, 5, 7, 11, 13];

/// The radical inverse of `index` in `base`: the Halton sequence's coordinate, in [0, 1).
fn radical_inverse(mut index: u32, base: u32) -> f32 {
    let mut result = 0.0;
    let mut digit_weight = 1.0 / base as f32;
    while index > 0 {
        result += (index % base) as f32 * digit_weight;
        index /= base;
        digit_weight /= base as f32;
    }
    result
}

impl<const C: usize> RbfNetwork<C> {
    /// Zero weights, centres on the Halton points 1..=C mapped to [-1, 1]^6.
    pub fn new() -> Self {
        Self {
            centres: core::array::from_fn(|i| {
                core::array::from_fn(|k| 2.0 * radical_inverse(i as u32 + 1, HALTON_BASES[k]) - 1.0)
            }),
            bias: [0.0; 3],
            linear: [[0.0; 3]; INPUTS],
            rbf: [[0.0; 3]; C],
        }
    }

    /// `nu_ad = W^T sigma` per channel (m/s^2).
    pub fn output(&self, basis: &Basis<C>) -> [f32; 3] {
        let mut out = self.bias;
        for (w, x) in self.linear.iter().zip(&basis.linear) {
            for ch in 0..3 {
                out[ch] += w[ch] * x;
            }
        }
        for (w, s) in self.rbf.iter().zip(&basis.rbf) {
            for ch in 0..3 {
                out[ch] += w[ch] * s;
            }
        }
        out
    }

    /// One Euler step of eq. 12 on channel `ch`:
    /// `W' = -Gamma (sigma e^T P B + kappa |e| W)`. Seed 002 prints the e-modification term
    /// with a plus sign; Narendra and Annaswamy's law (its ref. 16) subtracts it, which is what
    /// pulls the weights back, and the Lyapunov argument needs that sign with `nu_ad` entering
    /// the error dynamics as in eq. 10.
    pub fn learn(&mut self, ch: usize, basis: &Basis<C>, e_pb: f32, e_norm: f32, rates: Rates) {
        let leak = rates.e_modification * e_norm;
        let g = rates.learning_rate * rates.dt;
        self.bias[ch] -= g * (e_pb + leak * self.bias[ch]);
        for (w, x) in self.linear.iter_mut().zip(&basis.linear) {
            w[ch] -= g * (x * e_pb + leak * w[ch]);
        }
        for (w, s) in self.rbf.iter_mut().zip(&basis.rbf) {
            w[ch] -= g * (s * e_pb + leak * w[ch]);
        }
    }

    /// Norm of channel `ch`'s weight vector (bias, linear and Gaussian weights together).
    pub fn channel_norm(&self, ch: usize) -> f32 {
        let sum = self.bias[ch] * self.bias[ch]
            + self.linear.iter().map(|w| w[ch] * w[ch]).sum::<f32>()
            + self.rbf.iter().map(|w| w[ch] * w[ch]).sum::<f32>();
        sqrtf(sum)
    }

    /// Norm of all weights together (what is reported as the adaptive weight norm).
    pub fn norm(&self) -> f32 {
        let n: [f32; 3] = core::array::from_fn(|ch| self.channel_norm(ch));
        sqrtf(n.iter().map(|x| x * x).sum())
    }

    /// Projects channel `ch`'s weights back onto the ball of radius `bound`; true when they
    /// were outside it. A non-finite norm is left for the caller's fallback.
    pub fn project(&mut self, ch: usize, bound: f32) -> bool {
        let norm = self.channel_norm(ch);
        if norm <= bound || !norm.is_finite() {
            return false;
        }
        let k = bound / norm;
        self.bias[ch] *= k;
        for w in self.linear.iter_mut() {
            w[ch] *= k;
        }
        for w in self.rbf.iter_mut() {
            w[ch] *= k;
        }
        true
    }

    /// Forgets everything learned; the centres stay.
    pub fn reset_weights(&mut self) {
        self.bias = [0.0; 3];
        self.linear = [[0.0; 3]; INPUTS];
        self.rbf = [[0.0; 3]; C];
    }

    /// Sets channel `ch`'s bias weight (tests start from a learned state with it).
    #[cfg(test)]
    pub fn set_bias(&mut self, ch: usize, w: f32) {
        self.bias[ch] = w;
    }
}

/// The constants of one learning step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    pub learning_rate: f32,
    pub e_modification: f32,
    pub dt: f32,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn basis(n: &RbfNetwork<8>, v: [f32; 3]) -> Basis<8> {
        Basis::new(n, v, [0.0; 3], 1.0, 4.0, 0.6)
    }

    #[test]
    fn centres_fill_the_cube_and_the_nearest_basis_answers_most() {
        let n = RbfNetwork::<8>::new();
        for c in &n.centres {
            assert!(c.iter().all(|x| (-1.0..1.0).contains(x)), "{c:?}");
        }
        // Halton base 2: 1/2, 1/4, 3/4 -> 0, -0.5, 0.5.
        assert_eq!(
            [n.centres[0][0], n.centres[1][0], n.centres[2][0]],
            [0.0, -0.5, 0.5]
        );
        let at = n.centres[3];
        let b = Basis::new(
            &n,
            [at[0], at[1], at[2]],
            [4.0 * at[3], 4.0 * at[4], 4.0 * at[5]],
            1.0,
            4.0,
            0.6,
        );
        assert!((b.rbf[3] - 1.0).abs() < 1e-6);
        assert!(b.rbf.iter().enumerate().all(|(i, s)| i == 3 || *s < 1.0));
    }

    #[test]
    fn learning_moves_the_output_against_the_error_and_projection_bounds_it() {
        let mut n = RbfNetwork::<8>::new();
        let b = basis(&n, [0.3, 0.0, 0.0]);
        let rates = Rates {
            learning_rate: 10.0,
            e_modification: 0.0,
            dt: 0.01,
        };
        // e^T P B > 0: the vehicle lags its model, so nu_ad must fall (nu = ... - nu_ad rises).
        n.learn(2, &b, 0.5, 0.0, rates);
        assert!(n.output(&b)[2] < 0.0);
        assert_eq!(n.output(&b)[0], 0.0);
        for _ in 0..10_000 {
            n.learn(2, &b, 0.5, 0.0, rates);
            n.project(2, 3.0);
        }
        assert!((n.channel_norm(2) - 3.0).abs() < 1e-4);
        assert!(n.norm() <= 3.0 + 1e-4);
        n.reset_weights();
        assert_eq!(n.norm(), 0.0);
    }
}
