//! The point-to-line metric's sums of a pass ([`Metric::sums`](super::associate::Metric::sums)
//! for `icl`), four points at a time in `f32x4` lanes: moving the points, the distance and
//! residual gates, the dynamic test, the Cauchy weight and the twelve products a pair adds
//! (information, gradient, statistics) are lanewise; only fetching the partners and the
//! histogram are per point.
//!
//! The sums come out bit for bit as [`point_by_point`](super::associate::point_by_point)'s:
//! every product is rounded in the same order, a skipped point adds zeros, and each sum takes
//! its four points in order (the twelve products of a point are one row of a transposed 4x4
//! block, added to three accumulators). Sums kept per lane would save the transposes but round
//! differently, and then no longer reproduce a match. (Storing a pass's pairs as arrays and
//! summing them in a second, autovectorised loop was slower than the scalar loop: 217 k
//! instructions against 200 k a 360-beam match.)

use super::associate::{Pass, Tally, HIST_BINS, NO_PARTNER};
use super::linalg::Sym3;
use crate::geom::Vec2;
use wide::{f32x4, CmpGt, CmpNe};

/// The running sums: information (xx, xy, xt, yy), (yt, tt) and gradient (0, 1), gradient 2
/// and the statistics (weighted squares, weights, squares).
#[derive(Default)]
struct Sums {
    a: f32x4,
    b: f32x4,
    c: f32x4,
    inliers: u16,
    rejected_dynamic: u16,
}

/// [`Metric::sums`](super::associate::Metric::sums) of the point-to-line metric: the tally and
/// the gradient.
pub fn line_sums<const N: usize>(pass: &Pass<N>) -> (Tally, [f32; 3]) {
    let mut tally = Tally::default();
    let mut sums = Sums::default();
    let points = pass.points.chunks_exact(4);
    let slots = pass.slots.chunks_exact(4);
    let (last_points, last_slots) = (points.remainder(), slots.remainder());
    for (p, s) in points.zip(slots) {
        let (p, s) = (p.try_into().unwrap(), s.try_into().unwrap());
        add_four(pass, p, s, &mut sums, &mut tally.hist);
    }
    if !last_points.is_empty() {
        // The last few points, padded with points without a partner.
        let p = core::array::from_fn(|i| last_points.get(i).copied().unwrap_or(Vec2::ZERO));
        let s = core::array::from_fn(|i| last_slots.get(i).copied().unwrap_or(NO_PARTNER));
        add_four(pass, &p, &s, &mut sums, &mut tally.hist);
    }
    let ([xx, xy, xt, yy], [yt, tt, g0, g1], [g2, weighted_sq_sum, weight_sum, sq_sum]) =
        (sums.a.to_array(), sums.b.to_array(), sums.c.to_array());
    let stats = &mut tally.stats;
    stats.information = Sym3 {
        xx,
        xy,
        xt,
        yy,
        yt,
        tt,
    };
    stats.weighted_sq_sum = weighted_sq_sum;
    stats.weight_sum = weight_sum;
    stats.sq_sum = sq_sum;
    stats.inliers = sums.inliers;
    stats.rejected_dynamic = sums.rejected_dynamic;
    (tally, [g0, g1, g2])
}

#[inline(always)]
fn lanes(f: impl FnMut(usize) -> f32) -> f32x4 {
    f32x4::new(core::array::from_fn(f))
}

/// Adds four consecutive points `p` with partners `slots`.
#[inline(always)]
fn add_four<const N: usize>(
    pass: &Pass<N>,
    p: &[Vec2; 4],
    slots: &[u16; 4],
    sums: &mut Sums,
    hist: &mut [u16; HIST_BINS],
) {
    let reference = pass.reference;
    // Points without a partner fetch point 0 (any point would do): their lanes are masked.
    let j: [usize; 4] = core::array::from_fn(|i| match slots[i] {
        NO_PARTNER => 0,
        j => j as usize,
    });
    let target: [Vec2; 4] = core::array::from_fn(|i| reference.point(j[i]));
    // A point without a line gets the zero normal, which no unit normal rounds to.
    let normal: [Vec2; 4] =
        core::array::from_fn(|i| reference.line(j[i]).normal().unwrap_or(Vec2::ZERO));
    let (px, py) = (lanes(|i| p[i].x), lanes(|i| p[i].y));
    let (tx, ty) = (lanes(|i| target[i].x), lanes(|i| target[i].y));
    let (nx, ny) = (lanes(|i| normal[i].x), lanes(|i| normal[i].y));
    let partnered = lanes(|i| slots[i] as f32).cmp_ne(f32x4::splat(NO_PARTNER as f32));
    let zero = f32x4::splat(0.0);
    let lined = nx.cmp_ne(zero) | ny.cmp_ne(zero);

    // As `Pass::rotated` and `residual` round them.
    let (s, c) = (f32x4::splat(pass.sin), f32x4::splat(pass.cos));
    let (rx, ry) = (c * px - s * py, s * px + c * py);
    let (ox, oy) = (f32x4::splat(pass.pose.x), f32x4::splat(pass.pose.y));
    let (qx, qy) = (rx + ox, ry + oy);
    let (dx, dy) = (qx - tx, qy - ty);
    let far = (dx * dx + dy * dy).cmp_gt(f32x4::splat(pass.point_gate2));
    let r = nx * dx + ny * dy;
    let r2 = r * r;
    let paired = partnered & lined & !far;
    let dynamic = paired & r2.cmp_gt(f32x4::splat(pass.dynamic2));
    let inlier = paired & !dynamic & !r2.cmp_gt(f32x4::splat(pass.gate2));
    let w = f32x4::splat(1.0) / (f32x4::splat(1.0) + r2 * f32x4::splat(pass.inv_k2));

    // Outliers' factors are zeroed (not their products: a far point's may be infinite), so
    // they add zeros, which leave a sum that started at +0 unchanged.
    let (w, r, r2) = (w & inlier, r & inlier, r2 & inlier);
    // The information's Jacobian takes the rotated point, the gradient's q - t: they round
    // differently, as in `point_by_point` and `PointToLineGaussNewton::add`.
    let jt = (nx * -ry + ny * rx) & inlier;
    let jt_q = (nx * -(qy - oy) + ny * (qx - ox)) & inlier;
    let (wnx, wny, wjt) = (w * nx, w * ny, w * jt);
    let a = f32x4::transpose([wnx * nx, wnx * ny, wnx * jt, wny * ny]);
    let b = f32x4::transpose([wny * jt, wjt * jt, wnx * r, wny * r]);
    let c = f32x4::transpose([(w * jt_q) * r, w * r2, w, r2]);
    for i in 0..4 {
        sums.a += a[i];
        sums.b += b[i];
        sums.c += c[i];
    }

    let inliers = inlier.move_mask();
    sums.inliers += inliers.count_ones() as u16;
    sums.rejected_dynamic += dynamic.move_mask().count_ones() as u16;
    // The last bin as a float before truncating, which truncates to the same bin as the
    // integer minimum after it would (inliers' |r| are finite); outliers fall in bin 0 and add
    // nothing there. The mask of the index changes nothing but spares a bounds check.
    let last = f32x4::splat((HIST_BINS - 1) as f32);
    let bins = ((r.abs() * f32x4::splat(pass.bins_per_m)).fast_min(last) & inlier)
        .fast_trunc_int()
        .to_array();
    for (i, &bin) in bins.iter().enumerate() {
        let bin = bin as usize & (HIST_BINS - 1);
        hist[bin] = hist[bin].saturating_add((inliers >> i) as u16 & 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Pose2;
    use crate::matching::associate::point_by_point;
    use crate::matching::metrics::PointToLineGaussNewton;
    use crate::matching::prepared::PreparedScan;
    use crate::matching::MatchConfig;
    use crate::scan::{Beam, Scan};
    use proptest::prelude::*;

    /// A room of walls at `ranges` (each held for a run of beams), seen all round at 2 degrees.
    fn room(ranges: &[(f32, usize)], noise: &[f32]) -> PreparedScan<180> {
        let mut s: Scan<180> = Scan::new(0.0);
        let mut wall = ranges
            .iter()
            .flat_map(|&(r, n)| core::iter::repeat_n(r, n))
            .cycle();
        for (i, e) in noise.iter().enumerate() {
            let a = (-180.0f32 + 2.0 * i as f32).to_radians();
            let beam = match wall.next().unwrap() {
                r if r > 0.0 => Beam::new(a, r + e),
                _ => Beam::invalid(a),
            };
            s.push(beam).unwrap();
        }
        let mut p = PreparedScan::default();
        p.load(&s).unwrap();
        p.fit_lines(0.3, 0.05, 0.1);
        p
    }

    proptest! {
        /// The lanes' sums are the point-by-point sums, bit for bit: partners near and beyond
        /// the gates, missing, on points without a line, with and without the dynamic test,
        /// over point counts that leave every remainder of four.
        #[test]
        fn lanes_sum_exactly_what_the_points_sum(
            walls in proptest::collection::vec((prop_oneof![4 => 0.5f32..6.0, 1 => Just(0.0f32)], 2usize..40), 1..8),
            noise in proptest::collection::vec(-0.02f32..0.02, 360),
            partners in proptest::collection::vec(prop_oneof![8 => -2isize..=2, 1 => Just(500isize), 1 => Just(-1)], 180),
            cut in 0usize..8,
            (x, y, theta) in (-0.1f32..0.1, -0.1f32..0.1, -0.05f32..0.05),
            gate_m in 0.02f32..0.6,
            dynamic in prop_oneof![Just(None), (0.0001f32..0.01).prop_map(Some)],
        ) {
            let reference = room(&walls, &noise[..180]);
            let current = room(&walls, &noise[180..]);
            let points = &current.points()[..current.len().saturating_sub(cut)];
            // Near the point's own index, far (another part of the room), or none.
            let mut slots = [NO_PARTNER; 180];
            for (i, &d) in partners[..points.len()].iter().enumerate() {
                if d != -1 {
                    slots[i] = (i as isize + d).rem_euclid(reference.len() as isize) as u16;
                }
            }
            let slots = &slots[..points.len()];
            let cfg = MatchConfig::default();
            let pose = Pose2::new(x, y, theta);
            let pass = Pass {
                reference: &reference,
                points,
                slots,
                pose,
                cfg: &cfg,
                sin: libm::sinf(pose.theta),
                cos: libm::cosf(pose.theta),
                point_gate2: 0.25,
                gate2: gate_m * gate_m,
                dynamic2: dynamic.unwrap_or(f32::INFINITY),
                inv_k2: 1.0 / (gate_m * gate_m),
                bins_per_m: HIST_BINS as f32 / gate_m,
            };
            let (lanes, gradient) = line_sums(&pass);
            let (points, scalar) = point_by_point::<PointToLineGaussNewton, 180>(&pass);
            let bits = |t: &Tally, g: [f32; 3]| {
                let (s, i) = (&t.stats, &t.stats.information);
                let sums = [s.weighted_sq_sum, s.weight_sum, s.sq_sum, i.xx, i.xy, i.xt, i.yy, i.yt, i.tt];
                (sums.map(f32::to_bits), g.map(f32::to_bits), s.inliers, s.rejected_dynamic, t.hist)
            };
            prop_assert_eq!(bits(&lanes, gradient), bits(&points, scalar.gradient));
        }
    }
}
