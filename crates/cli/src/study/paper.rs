//! `plumbline study paper`: seed 000's own lidar experiments in the simulated room, with the
//! paper's method and Plumbline's side by side on the same flights.
//!
//! - Fig. 5: position drift of ICP and ICL over a flight around the room (no people).
//! - Fig. 7: a stationary lidar (the test pilot hovering over the start) while a person walks
//!   past, with and without sec. 4.2's rejection.
//!
//! The paper matches each revolution against the one before, so its methods (and `icp`, its
//! comparison) run with a keyframe at every scan; Plumbline's `icl` runs as it flies (keyframes,
//! its own rejection), and once more without rejection. The rejection rule as written has no
//! floor: with the previous displacement near zero (a lidar at rest, or the first revolution)
//! it rejects nearly every point and the estimate stops moving, so it also runs with the floor
//! Plumbline's `icl` uses.

use crate::plot::write_png;
use crate::report::{print_summary, CliError, CliResult};
use crate::sim::load_world;
use crate::sim::plot::{stacked_panels, Line};
use clap::Args;
use plotters::style::{RGBColor, BLACK};
use plumbline_core::geom::Pose2;
use plumbline_core::matching::{
    LidarOdometry, MatchConfig, MatcherKind, OdometryConfig, OdometryStep,
};
use plumbline_core::scan::Scan;
use plumbline_io::output::{self, OutputFile};
use plumbline_sim::runner::onboard_link::{fill_scan, XV11_BEAMS};
use plumbline_sim::runner::{Recorder, SimConfig, TruthPose};
use plumbline_sim::scenario::{self, Controller, Options};
use plumbline_sim::sensors::lidar::{LidarProfile, LidarScan};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PaperArgs {
    /// Directory for paper.tsv, fig5.png, fig7.png and summary.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of both flights.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// How long the lidar hovers while the person walks past (Fig. 7), s.
const STATIONARY_S: f64 = 30.0;

/// One method: its name in the table and plots, colour, and odometry configuration.
struct Method {
    name: &'static str,
    color: RGBColor,
    config: OdometryConfig,
}

fn methods() -> Vec<Method> {
    // The paper's setting: every revolution matched against the one before.
    let consecutive = |matcher: MatchConfig| OdometryConfig {
        matcher,
        keyframe_distance_m: 0.0,
        keyframe_angle_rad: 0.0,
        ..OdometryConfig::default()
    };
    let paper = MatchConfig::with_kind(MatcherKind::IclPaper);
    vec![
        Method {
            name: "icp",
            color: RGBColor(220, 40, 40),
            config: consecutive(MatchConfig::with_kind(MatcherKind::Icp)),
        },
        Method {
            name: "icl-paper",
            color: RGBColor(40, 90, 220),
            config: consecutive(paper),
        },
        Method {
            name: "icl-paper + sec. 4.2 rejection",
            color: RGBColor(170, 40, 200),
            config: consecutive(MatchConfig {
                paper_rejection: true,
                ..paper
            }),
        },
        Method {
            name: "icl-paper + rejection, 0.2 m floor",
            color: RGBColor(0, 170, 190),
            config: consecutive(MatchConfig {
                paper_rejection: true,
                paper_rejection_floor_m: MatchConfig::default().dynamic_floor_m,
                ..paper
            }),
        },
        Method {
            name: "icl (Plumbline)",
            color: RGBColor(20, 150, 60),
            config: OdometryConfig::default(),
        },
        Method {
            name: "icl (Plumbline), no rejection",
            color: RGBColor(230, 140, 20),
            config: OdometryConfig {
                matcher: MatchConfig {
                    dynamic_rejection: false,
                    ..MatchConfig::default()
                },
                ..OdometryConfig::default()
            },
        },
    ]
}

/// The scans of a flight with the true pose at each.
#[derive(Default)]
struct Scans(Vec<(LidarScan, TruthPose)>);

impl Recorder for Scans {
    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        self.0.push((scan.clone(), *truth));
    }
}

/// Flies `scenario` in the room with the test pilot, people walking or not.
fn fly(
    scenario: &str,
    people: bool,
    seed: u64,
    duration_s: Option<f64>,
) -> Result<Scans, CliError> {
    let lidar = LidarProfile::by_name("xv11").ok_or_else(|| CliError("no xv11 profile".into()))?;
    let mut config = SimConfig::new(load_world("room")?, lidar, seed);
    config.people = people;
    let options = Options {
        controller: Some(Controller::TestPilot),
        duration_s,
        ..Options::default()
    };
    let entry =
        scenario::find(scenario).ok_or_else(|| CliError(format!("no scenario {scenario}")))?;
    let flight = entry
        .prepare(&options, &mut config)
        .map_err(|e| CliError(format!("room {scenario}: {e}")))?;
    let mut scans = Scans::default();
    scenario::fly(&config, flight, &mut scans).map_err(|e| CliError(format!("room: {e}")))?;
    Ok(scans)
}

fn truth_pose(t: &TruthPose) -> Pose2 {
    Pose2::new(
        t.position.x as f32,
        t.position.y as f32,
        t.attitude.yaw() as f32,
    )
}

/// One method over one flight: per scan (t, estimated, true) positions relative to the first
/// scan's pose, in its frame; and the points it rejected, the matches that failed.
struct Track {
    samples: Vec<(f64, [f64; 2], [f64; 2])>,
    rejected: u64,
    failed: usize,
}

impl Track {
    fn errors(&self) -> impl Iterator<Item = f64> + '_ {
        self.samples
            .iter()
            .map(|(_, e, t)| ((e[0] - t[0]).powi(2) + (e[1] - t[1]).powi(2)).sqrt())
    }
}

fn track(scans: &Scans, config: OdometryConfig) -> Track {
    let mut odometry = Box::new(LidarOdometry::<XV11_BEAMS>::new(config));
    let mut scan: Box<Scan<XV11_BEAMS>> = Box::default();
    let origin = scans
        .0
        .first()
        .map_or(Pose2::IDENTITY, |(_, t)| truth_pose(t));
    let (mut rejected, mut failed) = (0u64, 0usize);
    let mut samples = Vec::with_capacity(scans.0.len());
    for (s, truth) in &scans.0 {
        fill_scan(s, &mut scan);
        match odometry.update(&scan, None) {
            OdometryStep::Matched { result, .. } => {
                rejected += u64::from(result.quality.rejected_dynamic);
            }
            OdometryStep::Predicted { .. } => failed += 1,
            OdometryStep::Started => {}
        }
        let e = odometry.pose();
        let t = origin.between(truth_pose(truth));
        samples.push((
            s.stamp_s,
            [f64::from(e.x), f64::from(e.y)],
            [f64::from(t.x), f64::from(t.y)],
        ));
    }
    Track {
        samples,
        rejected,
        failed,
    }
}

/// Accumulated dx and dy (the paper's axes) and the position error over time, every method.
fn panels(tracks: &[(&Method, Track)]) -> Vec<(&'static str, Vec<Line>)> {
    let axis = |i: usize| {
        let mut lines: Vec<Line> = tracks
            .iter()
            .map(|(m, t)| {
                (
                    m.name,
                    m.color,
                    t.samples.iter().map(|s| (s.0, s.1[i])).collect(),
                )
            })
            .collect();
        if let Some((_, t)) = tracks.first() {
            lines.push((
                "truth",
                BLACK,
                t.samples.iter().map(|s| (s.0, s.2[i])).collect(),
            ));
        }
        lines
    };
    let error: Vec<Line> = tracks
        .iter()
        .map(|(m, t)| {
            let times = t.samples.iter().map(|s| s.0);
            (m.name, m.color, times.zip(t.errors()).collect())
        })
        .collect();
    vec![
        ("accumulated dx from the start (m)", axis(0)),
        ("accumulated dy from the start (m)", axis(1)),
        ("position error against the truth (m)", error),
    ]
}

pub fn run(args: PaperArgs) -> CliResult {
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError(format!("--out {}: {e}", args.out.display())))?;
    let stage = |name: &str| OutputFile::stage(&args.out.join(name));
    let (fig5, fig7) = (stage("fig5.png")?, stage("fig7.png")?);
    let flights = [
        ("fig5", fly("survey", false, args.seed, None)?),
        ("fig7", fly("hold", true, args.seed, Some(STATIONARY_S))?),
    ];
    let methods = methods();
    let mut table = String::from(
        "figure\tmethod\tscans\tfailed_matches\trejected_points\tfinal_error_m\tmax_error_m\n",
    );
    let mut summary = serde_json::Map::new();
    for ((figure, scans), png) in flights.iter().zip([fig5, fig7]) {
        let tracks: Vec<(&Method, Track)> = methods
            .iter()
            .map(|m| (m, track(scans, m.config)))
            .collect();
        let mut rows = serde_json::Map::new();
        for (m, t) in &tracks {
            let last = t.errors().last().unwrap_or(f64::NAN);
            let max = t.errors().fold(0.0, f64::max);
            let _ = writeln!(
                table,
                "{figure}\t{}\t{}\t{}\t{}\t{last:.4}\t{max:.4}",
                m.name,
                t.samples.len(),
                t.failed,
                t.rejected
            );
            rows.insert(
                m.name.to_string(),
                json!({ "final_error_m": last, "max_error_m": max, "rejected_points": t.rejected,
                        "failed_matches": t.failed }),
            );
        }
        summary.insert(figure.to_string(), rows.into());
        write_png(png, |p| stacked_panels(p, panels(&tracks)))?;
    }
    output::write(&args.out.join("paper.tsv"), table.as_bytes())?;
    let summary = serde_json::Value::Object(summary);
    let text = serde_json::to_string_pretty(&summary).map_err(|e| CliError(e.to_string()))?;
    output::write(&args.out.join("summary.json"), (text + "\n").as_bytes())?;
    print_summary(&summary, args.json);
    Ok(())
}
