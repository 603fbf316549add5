//! Trajectories: one line per scan, `timestamp x y theta`, the timestamp copied exactly from the
//! scan it belongs to (DESIGN.md §5).
//!
//! Poses that were predicted rather than measured (the scan matcher failed, so the pose was
//! carried forward) keep their line, so the file still has one line per scan, and each run of
//! them is followed by a comment line `# lost FIRST LAST N` naming the first and last timestamp
//! of the run and its number of scans. Readers that skip `#` lines read the file as before;
//! [`read_trajectory`] marks those poses `lost` so that `eval` does not score them.

use crate::carmen::{OdomPose, ReadError};
use crate::text_table::read_rows_and_comments;
use std::io::Write;
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryPoint {
    pub timestamp_text: String,
    pub timestamp_s: f64,
    pub pose: OdomPose,
    /// Predicted across failed matches, not measured.
    pub lost: bool,
}

/// The word that starts the comment line closing a run of lost poses.
const LOST_TAG: &str = "lost";

/// Writes points as they come, closing each run of lost poses with its `# lost` line.
pub struct TrajectoryWriter<W: Write> {
    out: W,
    /// First timestamp and length of the run of lost poses being written, if one is open.
    lost_run: Option<(String, usize)>,
    last_text: String,
}

impl<W: Write> TrajectoryWriter<W> {
    pub fn new(out: W) -> Self {
        Self {
            out,
            lost_run: None,
            last_text: String::new(),
        }
    }

    pub fn push(&mut self, p: &TrajectoryPoint) -> std::io::Result<()> {
        if !p.lost {
            self.close_lost_run()?;
        }
        writeln!(
            self.out,
            "{} {:.6} {:.6} {:.6}",
            p.timestamp_text, p.pose.x_m, p.pose.y_m, p.pose.theta_rad
        )?;
        if p.lost {
            let run = self
                .lost_run
                .get_or_insert_with(|| (p.timestamp_text.clone(), 0));
            run.1 += 1;
        }
        self.last_text.clone_from(&p.timestamp_text);
        Ok(())
    }

    /// The underlying writer, for flushing it or asking about it between points.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// The underlying writer, mutably; the points already pushed are written into it.
    pub fn get_mut(&mut self) -> &mut W {
        &mut self.out
    }

    /// Closes an open run of lost poses and hands back the writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.close_lost_run()?;
        Ok(self.out)
    }

    fn close_lost_run(&mut self) -> std::io::Result<()> {
        if let Some((first, n)) = self.lost_run.take() {
            writeln!(
                self.out,
                "# {LOST_TAG} {first} {} {n} (poses predicted across failed matches, not measured)",
                self.last_text
            )?;
        }
        Ok(())
    }
}

pub fn write_trajectory<W: Write + ?Sized>(
    w: &mut W,
    points: &[TrajectoryPoint],
) -> std::io::Result<()> {
    let mut writer = TrajectoryWriter::new(w);
    for p in points {
        writer.push(p)?;
    }
    writer.finish().map(|_| ())
}

pub fn read_trajectory(path: &Path) -> Result<Vec<TrajectoryPoint>, ReadError> {
    let mut out: Vec<TrajectoryPoint> = Vec::new();
    let points = std::cell::RefCell::new(&mut out);
    read_rows_and_comments(
        path,
        4,
        |row| {
            let v = &row.values;
            points.borrow_mut().push(TrajectoryPoint {
                timestamp_text: row.first_text.to_string(),
                timestamp_s: v[0],
                pose: OdomPose {
                    x_m: v[1],
                    y_m: v[2],
                    theta_rad: v[3],
                },
                lost: false,
            });
            Ok(())
        },
        |comment| mark_lost(&mut points.borrow_mut(), comment),
    )?;
    Ok(out)
}

/// Marks the poses a `# lost FIRST LAST N` comment names; other comments are notes and ignored.
fn mark_lost(points: &mut [TrajectoryPoint], comment: &str) -> Result<(), String> {
    let mut fields = comment.split_ascii_whitespace();
    if fields.next() != Some(LOST_TAG) {
        return Ok(());
    }
    let (Some(first), Some(last), Some(n)) = (fields.next(), fields.next(), fields.next()) else {
        return Err(format!("`# {LOST_TAG}` needs FIRST LAST N"));
    };
    let n: usize = n
        .parse()
        .map_err(|_| format!("`# {LOST_TAG}`: scan count {n:?} is not a count"))?;
    let start = points.len().checked_sub(n).filter(|_| n > 0);
    let run = start.map(|k| &mut points[k..]);
    match run {
        Some(run) if run[0].timestamp_text == first && run[n - 1].timestamp_text == last => {
            run.iter_mut().for_each(|p| p.lost = true);
            Ok(())
        }
        _ => Err(format!(
            "`# {LOST_TAG} {first} {last} {n}` does not match the {n} pose(s) before it"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(t: &str, x: f64, lost: bool) -> TrajectoryPoint {
        TrajectoryPoint {
            timestamp_text: t.to_string(),
            timestamp_s: t.parse().unwrap(),
            pose: OdomPose::new(x, 0.0, 0.0),
            lost,
        }
    }

    fn round_trip(points: &[TrajectoryPoint]) -> (String, Vec<TrajectoryPoint>) {
        let mut text = Vec::new();
        write_trajectory(&mut text, points).unwrap();
        let path = std::env::temp_dir().join(format!(
            "plumbline-traj-{}-{}.txt",
            std::process::id(),
            points.len()
        ));
        std::fs::write(&path, &text).unwrap();
        let back = read_trajectory(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        (String::from_utf8(text).unwrap(), back)
    }

    #[test]
    fn lost_runs_are_closed_by_a_comment_and_read_back_as_lost() {
        let points = [
            point("1.5", 0.0, false),
            point("2.5", 1.0, true),
            point("3.5", 2.0, true),
            point("4.5", 3.0, false),
            point("5.5", 4.0, true),
        ];
        let (text, back) = round_trip(&points);
        assert_eq!(back, points);
        let comments: Vec<&str> = text.lines().filter(|l| l.starts_with('#')).collect();
        assert_eq!(comments.len(), 2, "{text}");
        assert!(comments[0].starts_with("# lost 2.5 3.5 2 "), "{text}");
        assert!(comments[1].starts_with("# lost 5.5 5.5 1 "), "{text}");
        // Without lost poses the file is exactly the plain `timestamp x y theta` rows.
        let plain = [point("1.5", 0.0, false), point("2.5", 1.0, false)];
        assert_eq!(
            round_trip(&plain).0,
            "1.5 0.000000 0.000000 0.000000\n2.5 1.000000 0.000000 0.000000\n"
        );
    }

    #[test]
    fn a_lost_comment_that_does_not_match_the_poses_before_it_is_an_error() {
        let mut points = vec![point("1.5", 0.0, false), point("2.5", 1.0, false)];
        assert!(mark_lost(&mut points, " lost 2.5 2.5 1").is_ok());
        assert!(points[1].lost && !points[0].lost);
        for bad in [
            " lost 1.5 2.5 3",
            " lost 9 2.5 1",
            " lost 2.5",
            " lost 2.5 2.5 x",
            " lost 2.5 2.5 0",
        ] {
            assert!(mark_lost(&mut points, bad).is_err(), "{bad}");
        }
        assert!(mark_lost(&mut points, " a note").is_ok());
    }
}
