//! Standard normal draws by the ziggurat method (Marsaglia and Tsang 2000, "The Ziggurat Method
//! for Generating Random Variables", 128 layers).
//!
//! Why not Box-Muller or the polar method: the simulator draws about a million normals per
//! simulated minute (IMU, lidar, gusts) and each polar draw costs two uniforms, a rejection loop
//! and a logarithm. The ziggurat takes one 64-bit word, a table look-up and a multiply for
//! about 99 % of draws; only the rare wedge and tail cases call `exp` or `ln`. The result is as
//! reproducible as before: the same seed gives the same stream, because the tables are computed
//! once by the same arithmetic on every run.
//!
//! Layout: the density f(x) = exp(-x²/2) is covered by 128 horizontal layers of equal area
//! `AREA`. Layer i is the rectangle 0 ≤ x < `edge[i]`, f(`edge[i]`) ≤ y < f(`edge[i + 1]`); layer 0
//! is the base strip plus the tail beyond `TAIL_START`, stretched to a rectangle of the same area.

use std::sync::OnceLock;

/// The uniform draws the method consumes. A trait rather than the simulator's generator itself,
/// so that the generator can offer normals through this module without the two depending on
/// each other; calls are monomorphised, so they inline as before.
pub trait UniformSource {
    /// 64 random bits.
    fn next_u64(&mut self) -> u64;
    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64;
}

const LAYERS: usize = 128;
/// Where the tail starts for 128 layers (Marsaglia and Tsang's r).
const TAIL_START: f64 = 3.442619855899;
/// The area of every layer, tail included (their v).
const AREA: f64 = 9.91256303526217e-3;

struct Tables {
    /// Right edge of each layer; `edge[LAYERS]` = 0.
    edge: [f64; LAYERS + 1],
    /// `edge[i + 1] / edge[i]`: a draw inside this fraction of layer i lies under the curve.
    inner: [f64; LAYERS],
    /// f(`edge[i]`).
    density: [f64; LAYERS + 1],
}

fn density(x: f64) -> f64 {
    (-0.5 * x * x).exp()
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut edge = [0.0; LAYERS + 1];
        edge[0] = AREA / density(TAIL_START);
        edge[1] = TAIL_START;
        for i in 1..LAYERS - 1 {
            edge[i + 1] = (-2.0 * (AREA / edge[i] + density(edge[i])).ln()).sqrt();
        }
        Tables {
            edge,
            inner: core::array::from_fn(|i| edge[i + 1] / edge[i]),
            density: edge.map(density),
        }
    })
}

/// One standard normal draw from `rng`. The common case (a point inside its layer's inner
/// rectangle) is small enough to inline into every caller; the rest is out of line.
#[inline]
pub fn standard_normal<R: UniformSource>(rng: &mut R) -> f64 {
    let t = tables();
    let (layer, u) = layer_and_offset(rng);
    if u.abs() < t.inner[layer] {
        return u * t.edge[layer];
    }
    outside_inner(rng, t, layer, u)
}

/// The low 7 bits of one word pick the layer, the top 53 give a signed uniform in [-1, 1).
#[inline]
fn layer_and_offset<R: UniformSource>(rng: &mut R) -> (usize, f64) {
    let bits = rng.next_u64();
    let layer = (bits & (LAYERS as u64 - 1)) as usize;
    let u = (bits >> 11) as f64 * (1.0 / (1u64 << 52) as f64) - 1.0;
    (layer, u)
}

/// A draw that fell outside its layer's inner rectangle: the tail, or the wedge test, drawing
/// afresh after a rejection.
#[cold]
#[inline(never)]
fn outside_inner<R: UniformSource>(rng: &mut R, t: &Tables, mut layer: usize, mut u: f64) -> f64 {
    loop {
        if layer == 0 {
            return tail(rng, u.signum());
        }
        let x = u * t.edge[layer];
        let y = t.density[layer] + rng.uniform() * (t.density[layer + 1] - t.density[layer]);
        if y < density(x) {
            return x;
        }
        (layer, u) = layer_and_offset(rng);
        if u.abs() < t.inner[layer] {
            return u * t.edge[layer];
        }
    }
}

/// A draw from the normal tail beyond `TAIL_START` (Marsaglia 1964), with the given sign.
fn tail<R: UniformSource>(rng: &mut R, sign: f64) -> f64 {
    loop {
        // 1 - uniform lies in (0, 1], so the logarithms are finite.
        let a = -(1.0 - rng.uniform()).ln() / TAIL_START;
        let b = -(1.0 - rng.uniform()).ln();
        if 2.0 * b > a * a {
            return sign * (TAIL_START + a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_layers_close_at_the_top() {
        // The recursion must end with a top layer of the common area reaching x = 0, or the
        // constants do not belong together.
        let t = tables();
        let top = t.edge[LAYERS - 1] * (1.0 - t.density[LAYERS - 1]);
        assert!((top - AREA).abs() < 1e-9, "top layer area {top}");
        assert_eq!(t.edge[LAYERS], 0.0);
        assert!(t.inner.iter().all(|&r| (0.0..1.0).contains(&r)));
    }

    #[test]
    fn the_distribution_function_matches_the_normal_one() {
        // Φ(x) for x = 0.5, 1, 2, 3, and the far tail beyond the base layer (3.5).
        let points = [
            (0.5, 0.691_462_461),
            (1.0, 0.841_344_746),
            (2.0, 0.977_249_868),
            (3.0, 0.998_650_102),
            (3.5, 0.999_767_371),
        ];
        let mut rng = Rng::new(99);
        let n = 1_000_000;
        let mut below = [0usize; 5];
        let mut above = [0usize; 5];
        for _ in 0..n {
            let z = standard_normal(&mut rng);
            for (k, &(x, _)) in points.iter().enumerate() {
                below[k] += usize::from(z < x);
                above[k] += usize::from(z > -x);
            }
        }
        for (k, &(x, phi)) in points.iter().enumerate() {
            for (side, count) in [("upper", below[k]), ("lower", above[k])] {
                let got = count as f64 / n as f64;
                let sigma = (phi * (1.0 - phi) / n as f64).sqrt();
                assert!(
                    (got - phi).abs() < 5.0 * sigma + 1e-6,
                    "{side} Φ({x}) = {got}, want {phi}"
                );
            }
        }
    }
}
