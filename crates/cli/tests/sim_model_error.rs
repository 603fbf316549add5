//! `plumbline sim`'s model-error options: values outside their ranges, and combinations the
//! vehicle cannot fly, are refused before anything is written, with the reason.

use std::process::Command;

fn sim(extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "sim",
        "--world",
        "hall",
        "--scenario",
        "hold",
        "--duration",
        "3",
        "--json",
    ];
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_plumbline"))
        .args(&args)
        .output()
        .unwrap()
}

#[test]
fn bad_model_errors_are_refused_with_the_reason() {
    let cases: [(&[&str], &str); 9] = [
        (&["--mass-scale", "3"], "[0.5, 2]"),
        (&["--mass-scale", "nan"], "[0.5, 2]"),
        (&["--weak-motor", "5,0.8"], "motors are 1, 2, 3, 4"),
        (&["--weak-motor", "1,0.2"], "[0.5, 1]"),
        (&["--weak-motor", "1"], "MOTOR,FACTOR"),
        (&["--cg-offset", "0.2,0"], "[-0.05, 0.05]"),
        (&["--payload-drop", "0.3,-2"], "must be >= 0"),
        (&["--gust-storm", "--no-gusts"], "cannot be used with"),
        (
            &["--mass-scale", "2", "--weak-motor", "2,0.5"],
            "balanced thrust",
        ),
    ];
    for (args, reason) in cases {
        let out = sim(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(stderr.contains(reason), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

#[test]
fn the_summary_records_the_injected_error() {
    let out = sim(&[
        "--mass-scale",
        "1.1",
        "--weak-motor",
        "3,0.9",
        "--gust-storm",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let last = String::from_utf8_lossy(&out.stdout)
        .lines()
        .last()
        .unwrap()
        .to_string();
    let summary: serde_json::Value = serde_json::from_str(&last).unwrap();
    let e = &summary["model_error"];
    assert_eq!(e["mass_scale"], 1.1);
    assert_eq!(e["weak_motor"]["motor"], 3);
    assert_eq!(e["gust_storm"], true);
    assert!(e["payload_drop"].is_null());
}
