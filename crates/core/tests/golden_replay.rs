//! The onboard stack's change indicator: a recorded input sequence (three seconds of a simulated
//! flight: IMU, sonar, XV-11 revolutions, the pilot's arm and kill switch) replayed through
//! `Onboard::step` (odometry, then `Autopilot::step`), every step's outputs compared with the
//! checked-in expected file to the last bit of their printed form.
//!
//! A change of behaviour anywhere onboard shows here as a diff of `golden/expected.txt`. When the
//! change is intended, regenerate the file in the same commit, so a reviewer sees what moved:
//! `bash scripts/golden.sh outputs` (the inputs: `bash scripts/golden.sh inputs`; formats in
//! `golden/README.md`).

use plumbline_core::flight::autopilot::AutopilotConfig;
use plumbline_core::flight::onboard::Onboard;
use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{ImuSample, Inputs, Outputs, PilotInput, SonarSample};
use plumbline_core::scan::{Beam, Scan};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Beams of an XV-11 revolution.
const BEAMS: usize = 360;

/// Set to regenerate the expected outputs instead of comparing with them.
const BLESS: &str = "PLUMBLINE_BLESS_GOLDEN";

/// One onboard step's inputs as recorded.
struct Step {
    dt_s: f32,
    inputs: Inputs,
    scan: Option<Scan<BEAMS>>,
}

fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name)
}

/// `fields[i]` parsed, or a panic naming the line and field.
fn field<T: std::str::FromStr>(fields: &[&str], i: usize, line: usize) -> T {
    let text = fields.get(i).unwrap_or_else(|| {
        panic!("inputs.txt:{line}: field {i} is missing");
    });
    text.parse()
        .unwrap_or_else(|_| panic!("inputs.txt:{line}: field {i} `{text}` is not a number"))
}

fn parse_inputs(text: &str) -> Vec<Step> {
    let mut steps: Vec<Step> = Vec::new();
    let mut pilot = PilotInput::default();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let f: Vec<&str> = raw.split_whitespace().collect();
        let Some(&kind) = f.first().filter(|k| !k.starts_with('#')) else {
            continue;
        };
        if kind == "step" {
            let t_s: f64 = field(&f, 1, line);
            steps.push(Step {
                dt_s: field(&f, 2, line),
                inputs: Inputs {
                    t_s,
                    imu: ImuSample {
                        t_s,
                        gyro_rad_s: [3, 4, 5].map(|i| field(&f, i, line)),
                        accel_m_s2: [6, 7, 8].map(|i| field(&f, i, line)),
                    },
                    sonar: None,
                    scan_match: None,
                    battery: None,
                    pilot,
                    mission: None,
                    companion: Default::default(),
                    ground: Default::default(),
                },
                scan: None,
            });
            continue;
        }
        let step = steps
            .last_mut()
            .unwrap_or_else(|| panic!("inputs.txt:{line}: `{kind}` before the first step"));
        match kind {
            "sonar" => {
                step.inputs.sonar = Some(SonarSample {
                    t_s: field(&f, 1, line),
                    range_m: field(&f, 2, line),
                })
            }
            "pilot" => {
                let flag = |i| field::<u8>(&f, i, line) != 0;
                pilot = PilotInput {
                    arm: flag(1),
                    manual: flag(2),
                    kill: flag(3),
                    roll_norm: field(&f, 4, line),
                    pitch_norm: field(&f, 5, line),
                    yaw_norm: field(&f, 6, line),
                    throttle_norm: field(&f, 7, line),
                };
                step.inputs.pilot = pilot;
            }
            "scan" => {
                let (start, increment, beam_dt): (f32, f32, f32) =
                    (field(&f, 2, line), field(&f, 3, line), field(&f, 4, line));
                let mut scan = Scan::new(field(&f, 1, line));
                for (k, range) in f[5..].iter().enumerate() {
                    let angle = start + increment * k as f32;
                    let mut beam = match *range {
                        "-" => Beam::invalid(angle),
                        _ => Beam::new(angle, field(&f, 5 + k, line)),
                    };
                    beam.time_offset_s = beam_dt * k as f32;
                    scan.push(beam)
                        .unwrap_or_else(|_| panic!("inputs.txt:{line}: more than {BEAMS} beams"));
                }
                step.scan = Some(scan);
            }
            _ => panic!("inputs.txt:{line}: unknown record `{kind}`"),
        }
    }
    steps
}

/// One step's outputs as one line; `{:?}` prints an `f32` with the fewest digits that read back
/// as the same bits, so equal text is equal values.
fn format_outputs(t_s: f64, o: &Outputs, out: &mut String) {
    let e = &o.estimate;
    let m = &o.motors.throttle_norm;
    let failsafe = o.failsafe.map_or("-".to_string(), |f| format!("{f:?}"));
    writeln!(
        out,
        "{t_s:.3} {:?} {failsafe} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} \
         {:?} {:?} {:?} {:?} {}",
        o.mode,
        m[0],
        m[1],
        m[2],
        m[3],
        e.position_m[0],
        e.position_m[1],
        e.position_m[2],
        e.velocity_m_s[0],
        e.velocity_m_s[1],
        e.velocity_m_s[2],
        e.roll_rad,
        e.pitch_rad,
        e.yaw_rad,
        e.position_std_m[0],
        e.position_std_m[1],
        e.position_std_m[2],
        e.valid,
    )
    .expect("writing to a String cannot fail");
}

#[test]
fn the_onboard_stack_replays_its_golden_flight_exactly() {
    let inputs = std::fs::read_to_string(golden("inputs.txt")).expect("golden/inputs.txt");
    let steps = parse_inputs(&inputs);
    let mut onboard = Onboard::<BEAMS>::new(OdometryConfig::default(), AutopilotConfig::default());
    let mut actual = String::from(
        "# Expected outputs of the golden replay (regenerate with `bash scripts/golden.sh outputs`).\n\
         # T_S MODE FAILSAFE MOTOR0..3 X Y Z VX VY VZ ROLL PITCH YAW STD_X STD_Y STD_Z VALID\n",
    );
    for step in &steps {
        let outputs = onboard.step(&step.inputs, step.scan.as_ref(), step.dt_s);
        format_outputs(step.inputs.t_s, &outputs, &mut actual);
    }
    // The replay must exercise what it guards: the matcher, the climb and the kill switch.
    let matched = onboard.autopilot().estimator_counters().scan_match.accepted;
    assert!(
        steps.len() >= 1000 && matched >= 5,
        "{} steps, {matched} matches",
        steps.len()
    );
    assert!([" Takeoff ", " Hold ", " Killed "]
        .iter()
        .all(|m| actual.contains(m)));

    let path = golden("expected.txt");
    if std::env::var_os(BLESS).is_some() {
        std::fs::write(&path, &actual).expect("writing golden/expected.txt");
        println!("wrote {}", path.display());
        return;
    }
    let expected = std::fs::read_to_string(&path).expect("golden/expected.txt");
    for (n, (want, got)) in expected.lines().zip(actual.lines()).enumerate() {
        assert_eq!(
            want,
            got,
            "golden/expected.txt:{}: the onboard stack's outputs changed (first difference; \
             if intended, run `bash scripts/golden.sh outputs` and commit the new file)",
            n + 1
        );
    }
    assert_eq!(
        expected.lines().count(),
        actual.lines().count(),
        "golden/expected.txt: a different number of steps"
    );
}
