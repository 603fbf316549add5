//! What `plumbline sim` records while it flies: the sensor logs and the ground truth, written
//! through `plumbline-io` as the samples arrive (`scans.clf`, `imu.csv`, `sonar.csv`,
//! `truth.txt`; `truth.relations` at the end), and the state series kept for the plots and the
//! progress bar. The files are staged and put in place when the flight is done, so a run that
//! fails or is stopped leaves the files of an earlier run as they were.

use crate::report::CliError;
use indicatif::ProgressBar;
use plumbline_core::msgs::{ImuSample, SonarSample};
use plumbline_io::carmen::{write_robotlaser1, LaserRecord, OdomPose};
use plumbline_io::output::OutputFile;
use plumbline_io::relations::{write_relation_3d, Relation3d};
use plumbline_io::sensor_csv::{write_imu, write_imu_header, write_sonar, write_sonar_header};
use plumbline_io::trajectory::{write_trajectory, TrajectoryPoint};
use plumbline_sim::runner::truth::relations;
use plumbline_sim::runner::{Recorder, StateSample, TruthPose};
use plumbline_sim::sensors::lidar::LidarScan;
use std::path::Path;

/// Relations pair scans this far apart at most, s.
const RELATION_SPAN_S: f64 = 10.0;

/// The files in `--out`, open while the flight streams into them.
pub struct SensorLogs {
    clf: OutputFile,
    imu: OutputFile,
    sonar: OutputFile,
    truth: OutputFile,
    /// The true pose of every scan, for the relations and the top view.
    poses: Vec<TruthPose>,
}

/// Stages `dir/name`; the old file stays until the flight is done.
pub fn create(dir: &Path, name: &str) -> Result<OutputFile, CliError> {
    Ok(OutputFile::stage(&dir.join(name))?)
}

impl SensorLogs {
    /// Creates the files in `dir` (and `dir` itself). Call only once the run is known to
    /// start, so that a refused run leaves nothing behind.
    pub fn create(dir: &Path) -> Result<Self, CliError> {
        let mut imu = create(dir, "imu.csv")?;
        let mut sonar = create(dir, "sonar.csv")?;
        write_imu_header(&mut imu)?;
        write_sonar_header(&mut sonar)?;
        Ok(Self {
            clf: create(dir, "scans.clf")?,
            imu,
            sonar,
            truth: create(dir, "truth.txt")?,
            poses: Vec::new(),
        })
    }

    /// Writes `truth.relations` and puts every file in place; returns the scans' true poses.
    pub fn finish(self, dir: &Path) -> Result<Vec<TruthPose>, CliError> {
        let mut rel = create(dir, "truth.relations")?;
        for r in relations(&self.poses, RELATION_SPAN_S) {
            let t = r.translation;
            let relation = Relation3d {
                t1_s: r.t1_s,
                t2_s: r.t2_s,
                translation_m: [t.x, t.y, t.z],
                roll_pitch_yaw_rad: [r.roll, r.pitch, r.yaw],
            };
            write_relation_3d(&mut rel, &relation)?;
        }
        for w in [self.clf, self.imu, self.sonar, self.truth, rel] {
            w.commit()?;
        }
        Ok(self.poses)
    }

    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) -> std::io::Result<()> {
        let mut rec = LaserRecord::new(
            scan.stamp_s,
            scan.start_angle_rad as f32,
            scan.increment_rad as f32,
            scan.max_range_m as f32,
            scan.ranges_m.clone(),
        );
        rec.valid.clone_from(&scan.valid);
        rec.timestamp_text = format!("{:.6}", scan.stamp_s);
        write_robotlaser1(&mut self.clf, &rec, "plumbline-sim")?;
        let p = truth.position;
        // `+ 0.0` turns an exact -0.0 heading into 0.0 so the file does not print "-0.000000".
        let point = TrajectoryPoint {
            timestamp_s: scan.stamp_s,
            pose: OdomPose::new(p.x, p.y, truth.attitude.yaw() + 0.0),
            timestamp_text: rec.timestamp_text,
            lost: false, // ground truth is never predicted
        };
        self.poses.push(*truth);
        write_trajectory(&mut self.truth, &[point])
    }
}

/// Receives the run: the files (with `--out`), the state series, the progress bar, and the
/// first write error (the run goes on; the command reports it at the end).
pub struct Collector {
    pub logs: Option<SensorLogs>,
    pub states: Vec<StateSample>,
    pub bar: ProgressBar,
    pub error: Option<std::io::Error>,
}

impl Collector {
    fn keep(&mut self, r: std::io::Result<()>) {
        if let Err(e) = r {
            self.error.get_or_insert(e);
        }
    }
}

impl Recorder for Collector {
    fn scan(&mut self, scan: &LidarScan, truth: &TruthPose) {
        if let Some(logs) = self.logs.as_mut() {
            let r = logs.scan(scan, truth);
            self.keep(r);
        }
    }

    fn imu(&mut self, s: &ImuSample) {
        if let Some(logs) = self.logs.as_mut() {
            let r = write_imu(&mut logs.imu, s);
            self.keep(r);
        }
    }

    fn sonar(&mut self, s: &SonarSample) {
        if let Some(logs) = self.logs.as_mut() {
            let r = write_sonar(&mut logs.sonar, s);
            self.keep(r);
        }
    }

    fn state(&mut self, s: &StateSample) {
        self.states.push(*s);
        self.bar.set_position(s.t_s as u64);
    }
}
