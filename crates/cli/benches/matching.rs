//! Match time per scan pair, single thread (DESIGN.md §6): median and 99th percentile.
//!
//! Pairs: consecutive real scans (the MIT CSAIL log when ../shared/data is present, otherwise
//! the bundled Intel excerpt), and synthetic 360- and 1440-beam revolutions ray-cast in the
//! simulator's `office` world along a path. Every pair is timed from scratch (reference
//! preparation included) with an identity initial guess, like the peers it is compared with.
//! The pairs are also written to target/bench-pairs/*.txt so `scripts/peer_bench.py` can time a
//! peer library on exactly the same input.
//!
//! Run: `cargo bench -p plumbline --bench matching`

use plumbline_core::geom::Pose2;
use plumbline_core::matching::{MatchConfig, MatcherKind, ScanMatcher};
use plumbline_core::scan::{Beam, Scan};
use plumbline_io::carmen::{read_log, ReadOptions};
use plumbline_sim::math::Vec3;
use plumbline_sim::world::scene::Scene;
use plumbline_sim::world::World;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

const N: usize = 1440;
const REPEATS: usize = 5;

fn real_pairs() -> (String, Vec<(Scan<N>, Scan<N>)>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mit = root.join("../shared/data/mit-csail/mit-csail.clf");
    let (name, path) = if mit.exists() {
        ("mit-csail-361".to_string(), mit)
    } else {
        eprintln!(
            "../shared/data not found: timing the bundled Intel excerpt instead of MIT CSAIL"
        );
        (
            "intel-excerpt-180".to_string(),
            root.join("data/intel-excerpt.clf"),
        )
    };
    let log = read_log(&path, &ReadOptions::default()).expect("bench log");
    let scans: Vec<Scan<N>> = log
        .scans
        .iter()
        .take(301)
        .map(|r| r.to_scan().unwrap())
        .collect();
    (
        name,
        scans
            .windows(2)
            .map(|w| (w[0].clone(), w[1].clone()))
            .collect(),
    )
}

fn synthetic_pairs(beams: usize) -> Vec<(Scan<N>, Scan<N>)> {
    let world = World::shipped("office")
        .expect("office world")
        .expect("valid office world");
    let scene = Scene::new(&world);
    let start = world.start_position();
    let scan_at = |x: f64, y: f64, th: f64, seed: u64| -> Scan<N> {
        let mut s = Scan::new(0.0);
        let mut rng = plumbline_sim::rng::Rng::new(seed);
        for i in 0..beams {
            let a = std::f64::consts::TAU * i as f64 / beams as f64 - std::f64::consts::PI;
            let d = Vec3::new((th + a).cos(), (th + a).sin(), 0.0);
            let beam = match scene.cast(Vec3::new(x, y, 1.0), d, 12.0, &[]) {
                Some(hit) => Beam::new(a as f32, (hit.range_m + 0.01 * rng.gauss()) as f32),
                None => Beam::invalid(a as f32),
            };
            s.push(beam).unwrap();
        }
        s
    };
    (0..100)
        .map(|k| {
            let t = k as f64;
            let (x, y, th) = (
                start.x + 0.05 * t,
                start.y + 0.01 * (t * 0.3).sin(),
                0.02 * t,
            );
            (
                scan_at(x, y, th, 2 * k as u64),
                scan_at(x + 0.05, y + 0.01, th + 0.02, 2 * k as u64 + 1),
            )
        })
        .collect()
}

/// Median and 99th percentile of the per-pair best-of-`REPEATS` time, µs, the failed pairs, and
/// the mean Gauss-Newton passes per match (what most of the time scales with). Never inlined, so
/// callgrind can count only the matching: `--toggle-collect='*time_pairs*'`.
#[inline(never)]
fn time_pairs(kind: MatcherKind, pairs: &[(Scan<N>, Scan<N>)]) -> (f64, f64, usize, f64) {
    let mut matcher: Box<ScanMatcher<N>> = Box::new(ScanMatcher::new(MatchConfig::with_kind(kind)));
    let mut times = Vec::with_capacity(pairs.len());
    let mut failed = 0;
    let mut passes = 0usize;
    for (a, b) in pairs {
        let mut best = f64::INFINITY;
        for _ in 0..REPEATS {
            let t0 = Instant::now();
            let result = matcher
                .set_reference(a)
                .ok()
                .and_then(|()| matcher.match_scan(b, Pose2::IDENTITY).ok());
            best = best.min(t0.elapsed().as_secs_f64() * 1e6);
            failed += result.is_none() as usize;
            passes += result.map_or(0, |r| r.quality.iterations as usize);
        }
        times.push(best);
    }
    times.sort_by(f64::total_cmp);
    let pick = |p: f64| times[((times.len() as f64 * p).ceil() as usize).clamp(1, times.len()) - 1];
    let mean_passes = passes as f64 / (REPEATS * pairs.len()).max(1) as f64;
    (pick(0.5), pick(0.99), failed / REPEATS, mean_passes)
}

fn dump(name: &str, pairs: &[(Scan<N>, Scan<N>)]) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/bench-pairs");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.txt"));
    let mut w = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    for (a, b) in pairs {
        for s in [a, b] {
            let pts: Vec<String> = s
                .beams()
                .iter()
                .filter(|b| b.valid)
                .map(|b| b.point())
                .map(|p| format!("{} {}", p.x, p.y))
                .collect();
            writeln!(w, "{}", pts.join(" ")).unwrap();
        }
    }
    path
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --benches` passes nothing and only wants it to run.
    let quick = !std::env::args().any(|a| a == "--bench");
    // Optional filters: `cargo bench --bench matching -- icl office-360` times only the rows whose
    // pair set or matcher is named by every filter word.
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let wanted =
        |name: &str, kind: MatcherKind| filters.iter().all(|f| f == name || f == kind.name());
    let (real_name, mut real) = real_pairs();
    let mut sets = vec![
        (real_name, real.clone()),
        ("office-360".to_string(), synthetic_pairs(360)),
        ("office-1440".to_string(), synthetic_pairs(1440)),
    ];
    if quick {
        real.truncate(3);
        for s in &mut sets {
            s.1.truncate(3);
        }
    }
    let mut rows = Vec::new();
    for (name, pairs) in &sets {
        let file = dump(name, pairs);
        for kind in MatcherKind::ALL {
            if kind == MatcherKind::IclPaper && name.contains("1440") {
                continue; // O(N²) by design; minutes per run at 1440 beams.
            }
            if !wanted(name, kind) {
                continue;
            }
            let (median, p99, failed, passes) = time_pairs(kind, pairs);
            println!(
                "{name:<18} {:<10} median {median:8.1} us  p99 {p99:8.1} us  failed {failed}/{}  passes {passes:.1}",
                kind.name(),
                pairs.len()
            );
            rows.push(serde_json::json!({"pairs": name, "matcher": kind.name(), "median_us": median, "p99_us": p99, "failed": failed, "passes_mean": passes, "file": file}));
        }
    }
    println!("{}", serde_json::Value::Array(rows));
}
