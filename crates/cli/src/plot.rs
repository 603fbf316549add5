//! PNG plotting shared by the subcommands.
//!
//! Text needs a font; plotters' `ab_glyph` backend takes one at run time. We register DejaVu Sans
//! from the system (Debian's fonts-dejavu-core, present on the project's machines). Without it
//! plots are still drawn, only without captions and tick labels.

use std::sync::OnceLock;

const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// True when a font was registered, so callers may draw text.
pub fn fonts_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        FONT_PATHS.iter().any(|path| {
            let Ok(bytes) = std::fs::read(path) else {
                return false;
            };
            let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, leaked)
                .is_ok()
        })
    })
}

use crate::report::{CliError, CliResult};
use plotters::prelude::*;
use plumbline_io::carmen::{LaserRecord, OdomPose};
use plumbline_io::output::OutputFile;
use plumbline_io::trajectory::TrajectoryPoint;
use std::path::Path;

/// Plots are PNG files, and the encoder picks the format by the name: refuse any other name up
/// front, before any work, with what to do instead.
fn require_png(option: &str, path: &Path) -> Result<(), CliError> {
    let is_png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if is_png {
        Ok(())
    } else {
        Err(CliError(format!(
            "{option} {}: plots are written as PNG; give a file name ending in .png",
            path.display()
        )))
    }
}

/// A PNG output, staged: the name checked and the file creatable before any work is done.
pub fn stage_png(option: &str, path: &Path) -> Result<OutputFile, CliError> {
    require_png(option, path)?;
    Ok(OutputFile::stage(path)?)
}

/// Draws into a staged PNG and puts it in place, so an existing picture is only ever replaced
/// by a finished one; `draw` renders into the path it is given.
pub fn write_png(
    out: OutputFile,
    draw: impl FnOnce(&Path) -> Result<(), Box<dyn std::error::Error>>,
) -> CliResult {
    draw(out.current_path()).map_err(|e| CliError(format!("{}: {e}", out.shown())))?;
    Ok(out.commit()?)
}

/// Enough scans to show the walls without drawing millions of pixels.
const PLOT_SCANS: usize = 800;
/// Path points kept; a path is drawn as a line, so more would not show.
const PLOT_PATH_POINTS: usize = 20_000;

/// Every `stride`-th item of a stream, the stride doubling whenever twice `keep` are held, so
/// between `keep` and `2 keep` evenly spaced items are held however long the stream is.
struct EvenSample<T> {
    keep: usize,
    stride: usize,
    next_index: usize,
    items: Vec<(usize, T)>,
}

impl<T> EvenSample<T> {
    fn new(keep: usize) -> Self {
        Self {
            keep,
            stride: 1,
            next_index: 0,
            items: Vec::new(),
        }
    }

    fn push(&mut self, make: impl FnOnce() -> T) {
        let i = self.next_index;
        self.next_index += 1;
        if !i.is_multiple_of(self.stride) {
            return;
        }
        self.items.push((i, make()));
        if self.items.len() >= 2 * self.keep {
            self.stride *= 2;
            let stride = self.stride;
            self.items.retain(|(k, _)| k.is_multiple_of(stride));
        }
    }
}

/// What the trajectory plot needs from a run, gathered as scans go by with bounded memory.
pub struct TrajectoryPlot {
    scans: EvenSample<(LaserRecord, OdomPose)>,
    path: EvenSample<(f64, f64)>,
    last: Option<(f64, f64)>,
}

impl TrajectoryPlot {
    pub fn new() -> Self {
        Self {
            scans: EvenSample::new(PLOT_SCANS),
            path: EvenSample::new(PLOT_PATH_POINTS),
            last: None,
        }
    }

    pub fn add(&mut self, rec: &LaserRecord, pose: OdomPose) {
        self.scans.push(|| (rec.clone(), pose));
        self.path.push(|| (pose.x_m, pose.y_m));
        self.last = Some((pose.x_m, pose.y_m));
    }
}

/// The scans a trajectory plot draws, sampled as they stream by before their poses are final
/// (SLAM places them only once its pose graph is optimised): the same sample
/// [`TrajectoryPlot::add`] keeps, so both commands draw the same scans.
pub struct PlotScans(EvenSample<LaserRecord>);

impl PlotScans {
    pub fn new() -> Self {
        Self(EvenSample::new(PLOT_SCANS))
    }

    pub fn add(&mut self, rec: &LaserRecord) {
        self.0.push(|| rec.clone());
    }

    /// The plot with each sampled scan at its pose in `trajectory`, which holds one point for
    /// every scan added, in order.
    pub fn place(self, trajectory: &[TrajectoryPoint]) -> TrajectoryPlot {
        let mut plot = TrajectoryPlot::new();
        for point in trajectory {
            plot.path.push(|| (point.pose.x_m, point.pose.y_m));
            plot.last = Some((point.pose.x_m, point.pose.y_m));
        }
        plot.scans.items = self
            .0
            .items
            .into_iter()
            .filter_map(|(i, rec)| trajectory.get(i).map(|p| (i, (rec, p.pose))))
            .collect();
        plot
    }
}

/// Top view: sampled scans' points placed by their estimated pose (grey), the path on top
/// (red). A good trajectory draws crisp walls; drift shows as doubled or smeared walls.
pub fn plot_trajectory(
    path: &Path,
    data: &TrajectoryPlot,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut cloud = Vec::new();
    for (_, (rec, p)) in &data.scans.items {
        let (s, c) = p.theta_rad.sin_cos();
        for (i, (&r, &ok)) in rec.ranges_m.iter().zip(&rec.valid).enumerate() {
            if ok && r < 30.0 {
                let a = (rec.start_angle_rad + rec.increment_rad * i as f32) as f64;
                let (lx, ly) = (r as f64 * a.cos(), r as f64 * a.sin());
                cloud.push((c * lx - s * ly + p.x_m, s * lx + c * ly + p.y_m));
            }
        }
    }
    let mut path_xy: Vec<(f64, f64)> = data.path.items.iter().map(|(_, p)| *p).collect();
    path_xy.extend(data.last.filter(|l| path_xy.last() != Some(l)));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in cloud.iter().chain(&path_xy) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
    }
    // Equal scale on both axes so rooms keep their shape.
    let span = (x1 - x0).max(y1 - y0).max(1.0) * 1.05;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let root = BitMapBackend::new(path, (1000, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let labels = fonts_available();
    let mut builder = ChartBuilder::on(&root);
    builder.margin(10);
    if labels {
        builder
            .caption("trajectory over scan points (m)", ("sans-serif", 20))
            .x_label_area_size(30)
            .y_label_area_size(40);
    }
    let mut chart = builder.build_cartesian_2d(
        cx - span / 2.0..cx + span / 2.0,
        cy - span / 2.0..cy + span / 2.0,
    )?;
    if labels {
        chart.configure_mesh().disable_mesh().draw()?;
    }
    chart.draw_series(cloud.iter().map(|&p| Pixel::new(p, RGBColor(90, 90, 90))))?;
    chart.draw_series(LineSeries::new(path_xy, RED.stroke_width(2)))?;
    root.present()?;
    Ok(())
}
