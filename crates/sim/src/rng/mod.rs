//! Randomness for the simulator: a small seeded generator (xoshiro256++, seeded through splitmix64) with Gaussian draws
//! (the [`ziggurat`] method).
//!
//! The simulator's promise is bit-for-bit reproducibility from one `u64` seed on every platform.
//! Owning the 40 lines of generator means no upstream release can change a stream under us, and
//! each random process gets its own stream via [`Rng::fork`], so adding a sensor does not shift
//! the noise of the others.

pub mod ziggurat;

/// xoshiro256++ (Blackman and Vigna), period 2^256 - 1.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
}

fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        let mut sm = seed;
        Self {
            s: core::array::from_fn(|_| splitmix64(&mut sm)),
        }
    }

    /// An independent stream for one named process (`stream` distinguishes siblings).
    pub fn fork(seed: u64, stream: u64) -> Self {
        Self::new(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03))
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.uniform() < p
    }

    /// Standard normal.
    #[inline]
    pub fn gauss(&mut self) -> f64 {
        ziggurat::standard_normal(self)
    }
}

impl ziggurat::UniformSource for Rng {
    #[inline]
    fn next_u64(&mut self) -> u64 {
        Rng::next_u64(self)
    }
    #[inline]
    fn uniform(&mut self) -> f64 {
        Rng::uniform(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_moments_match_over_many_samples() {
        let mut rng = Rng::new(7);
        let n = 200_000;
        let (mut sum, mut sum2, mut sum4) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let z = rng.gauss();
            sum += z;
            sum2 += z * z;
            sum4 += z * z * z * z;
        }
        let (mean, var, kurt) = (sum / n as f64, sum2 / n as f64, sum4 / n as f64);
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.01, "variance {var}");
        assert!((kurt - 3.0).abs() < 0.05, "fourth moment {kurt}");
    }

    #[test]
    fn same_seed_same_stream_other_seed_differs() {
        let a: Vec<u64> = (0..8)
            .scan(Rng::new(1), |r, _| Some(r.next_u64()))
            .collect();
        let b: Vec<u64> = (0..8)
            .scan(Rng::new(1), |r, _| Some(r.next_u64()))
            .collect();
        let c: Vec<u64> = (0..8)
            .scan(Rng::new(2), |r, _| Some(r.next_u64()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(Rng::fork(1, 1).next_u64(), Rng::fork(1, 2).next_u64());
    }
}
