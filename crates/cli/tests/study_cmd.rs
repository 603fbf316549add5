//! `plumbline study`: a tiny sweep runs end to end, writes its table, summary and plots, and
//! reproduces them exactly whatever the thread count.

mod support;

use support::{entries, last_json, p, run, scratch, stderr};

fn tiny_sweep(out: &std::path::Path, threads: &str) -> std::process::Output {
    run(&[
        "study",
        "energy",
        "--out",
        p(out),
        "--position-kp",
        "1,2",
        "--velocity-kp",
        "4",
        "--command-tau",
        "0.1",
        "--seeds",
        "1",
        "--seed",
        "3",
        "--duration",
        "8",
        "--threads",
        threads,
        "--json",
    ])
}

#[test]
fn a_tiny_energy_sweep_writes_its_table_and_plots_and_reproduces_exactly() {
    let dir = scratch("study-energy");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let out_a = tiny_sweep(&a, "1");
    assert!(out_a.status.success(), "{}", stderr(&out_a));
    let out_b = tiny_sweep(&b, "2");
    assert!(out_b.status.success(), "{}", stderr(&out_b));
    assert_eq!(
        entries(&a),
        [
            "energy.tsv",
            "excess.png",
            "pareto.png",
            "power.png",
            "summary.json"
        ]
    );
    let table = std::fs::read_to_string(a.join("energy.tsv")).unwrap();
    // The header, the default tuning, and the two settings of the grid.
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 4, "{table}");
    assert!(
        rows[1].starts_with("pid\tdefault\tdefault\tdefault\t0\t"),
        "{table}"
    );
    assert!(rows[2].starts_with("pid\t1\t4\t0.1\t"), "{table}");
    assert!(rows[3].starts_with("pid\t2\t4\t0.1\t"), "{table}");
    for name in ["energy.tsv", "summary.json"] {
        assert_eq!(
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
            "{name} differs between one and two threads"
        );
    }
    let s = last_json(&out_a);
    assert_eq!(
        (s["settings"].as_u64(), s["flights"].as_u64()),
        (Some(3), Some(3))
    );
    let pid = &s["controllers"]["pid"];
    let error = pid["default_rms_hold_error_m"].as_f64().unwrap();
    let power = pid["default_hold_power_w"].as_f64().unwrap();
    assert!(error > 0.0 && error < 0.5, "{s}");
    // The F450 hovers on about 130 W; a hold must be near that, not zero or runaway.
    assert!((100.0..170.0).contains(&power), "{s}");
    // The floor is the flown vehicle's still hover: the hold spends a little above it, and
    // the bound the summary states is that excess.
    let floor = pid["default_still_hover_w"].as_f64().unwrap();
    let over = pid["default_over_still_hover"].as_f64().unwrap();
    assert!(floor < power && over > 0.0 && over < 0.05, "{s}");
    let bound = pid["bound"].as_str().unwrap();
    assert!(
        bound.contains(&format!("{:.2} %", 100.0 * over)),
        "{bound} against {over}"
    );
    let header: Vec<&str> = rows[0].split('\t').collect();
    for column in ["still_hover_w", "excess_w", "tilt_w", "predicted_excess_w"] {
        assert!(header.contains(&column), "{column} missing: {}", rows[0]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_gain_outside_its_range_is_refused_before_any_flight() {
    let dir = scratch("study-energy-bad");
    let out = run(&["study", "energy", "--out", p(&dir), "--position-kp", "1,9"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("[0.1, 5]"), "{}", stderr(&out));
    assert!(entries(&dir).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
