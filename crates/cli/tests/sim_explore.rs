//! `plumbline sim --scenario explore`: the summary's exploration keys, the plots, the choice of
//! guidance, and a seeded run that repeats exactly. Short runs; the targets are benchmarks.

mod support;

use serde_json::Value;
use support::{run as plumbline, scratch};

fn explore(guidance: &str, out: &std::path::Path) -> Value {
    let out = plumbline(&[
        "sim",
        "--world",
        "office",
        "--scenario",
        "explore",
        "--lidar",
        "xv11",
        "--guidance",
        guidance,
        "--seed",
        "2",
        "--duration",
        "20",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap()).unwrap()
}

/// The summary without the wall-clock figures.
fn simulated(mut v: Value) -> Value {
    let map = v.as_object_mut().unwrap();
    map.remove("wall_seconds");
    map.remove("realtime_factor");
    v
}

#[test]
fn an_exploration_reports_its_keys_draws_its_plots_and_repeats_exactly() {
    let dir = scratch("explore");
    let (a_dir, b_dir) = (dir.join("a"), dir.join("b"));
    let a = explore("frontier", &a_dir);
    for key in [
        "explored_fraction",
        "time_to_90pct_s",
        "collisions",
        "min_clearance_m",
        "returned_home",
        "home_error_m",
        "landed",
        "map_error_m",
        "distance_flown_m",
        "energy_wh",
        "realtime_factor",
        "failsafe",
    ] {
        assert!(a.get(key).is_some(), "{key} missing: {a}");
    }
    assert_eq!(a["guidance"], "frontier");
    assert_eq!(a["collisions"], 0, "{a}");
    let seen = a["explored_fraction"].as_f64().unwrap();
    assert!(seen > 0.0 && seen <= 1.0, "{a}");
    for png in ["map.png", "explored.png", "top.png"] {
        let bytes = std::fs::read(a_dir.join(png)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{png}");
    }
    let b = explore("frontier", &b_dir);
    assert_eq!(simulated(a), simulated(b));
    let truth = |d: &std::path::Path| std::fs::read(d.join("truth.txt")).unwrap();
    assert_eq!(truth(&a_dir), truth(&b_dir));
    let w = explore("wall-follow", &dir.join("w"));
    assert_eq!(w["guidance"], "wall-follow");
}

#[test]
fn an_unknown_guidance_is_refused_with_the_choices() {
    let out = plumbline(&["sim", "--scenario", "explore", "--guidance", "spiral"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("frontier") && err.contains("wall-follow"),
        "{err}"
    );
}
