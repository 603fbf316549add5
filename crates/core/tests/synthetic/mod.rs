//! Known worlds and scans ray-cast in them, shared by the synthetic matching tests.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::{Beam, Scan};

pub type Seg = (Vec2, Vec2);

/// A 6 m x 4 m room with a pillar and an alcove: enough structure to pin all three DOF.
pub fn room() -> Vec<Seg> {
    let poly = |pts: &[(f32, f32)]| -> Vec<Seg> {
        (0..pts.len())
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                (Vec2::new(a.0, a.1), Vec2::new(b.0, b.1))
            })
            .collect()
    };
    let mut w = poly(&[
        (-3.0, -2.0),
        (3.0, -2.0),
        (3.0, 0.5),
        (3.6, 0.5),
        (3.6, 1.2),
        (3.0, 1.2),
        (3.0, 2.0),
        (-3.0, 2.0),
    ]);
    w.extend(poly(&[(-1.0, 0.6), (-0.6, 0.6), (-0.6, 1.0), (-1.0, 1.0)]));
    w
}

/// Two long parallel walls: a corridor with no feature along x.
pub fn corridor() -> Vec<Seg> {
    vec![
        (Vec2::new(-50.0, -1.0), Vec2::new(50.0, -1.0)),
        (Vec2::new(-50.0, 1.0), Vec2::new(50.0, 1.0)),
    ]
}

pub fn cast(world: &[Seg], origin: Vec2, dir: Vec2) -> Option<f32> {
    let mut best: Option<f32> = None;
    for &(a, b) in world {
        let e = b - a;
        let denom = dir.cross(e);
        if denom.abs() < 1e-9 {
            continue;
        }
        let w = a - origin;
        let t = w.cross(e) / denom;
        let u = w.cross(dir) / denom;
        if t > 1e-4 && (0.0..=1.0).contains(&u) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

/// A scan from `pose`: `beams` beams over `fov` centred ahead, Gaussian-ish noise from a seeded LCG.
pub fn scan<const N: usize>(
    world: &[Seg],
    pose: Pose2,
    beams: usize,
    fov: f32,
    noise: f32,
    seed: u64,
) -> Scan<N> {
    scan_within(world, pose, beams, fov, noise, seed, 12.0)
}

/// [`scan`] with a lidar that sees no farther than `max_range_m` (farther hits are no return).
pub fn scan_within<const N: usize>(
    world: &[Seg],
    pose: Pose2,
    beams: usize,
    fov: f32,
    noise: f32,
    seed: u64,
    max_range_m: f32,
) -> Scan<N> {
    let mut rng = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut uniform = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    let full = fov >= std::f32::consts::TAU - 1e-3;
    let step = if full {
        fov / beams as f32
    } else {
        fov / (beams - 1) as f32
    };
    let mut s = Scan::new(0.0);
    for i in 0..beams {
        let a = -fov / 2.0 + step * i as f32;
        let dir = pose.rotate(Vec2::new(a.cos(), a.sin()));
        let r = cast(world, pose.translation(), dir).filter(|&r| r < max_range_m);
        // Sum of three uniforms: roughly Gaussian with standard deviation `noise`.
        let n = noise * 2.0 * (uniform() + uniform() + uniform());
        s.push(match r {
            Some(r) => Beam::new(a, r + n),
            None => Beam::invalid(a),
        })
        .unwrap();
    }
    s
}
