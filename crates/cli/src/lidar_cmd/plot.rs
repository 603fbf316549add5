//! `plumbline lidar plot --device D CAPTURE [--revolution N] --out PNG`: one revolution seen
//! from above, x forward (up the page), y left, so the picture matches the robot's view.

use super::require_frames;
use crate::plot::{stage_png, write_png};
use crate::report::{CliError, CliResult};
use clap::Args;
use plotters::prelude::*;
use plumbline_io::input::open_input;
use plumbline_io::output::check_distinct;
use plumbline_io::serial::{decode_stream, DecodedScan, Device};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct PlotArgs {
    /// xv11 | xv11-old | urg | rplidar
    #[arg(long)]
    device: Device,
    capture: PathBuf,
    /// Which revolution (0 = the first handed out; often partial).
    #[arg(long, default_value_t = 1)]
    revolution: usize,
    /// The picture (a `.png` file).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(a: PlotArgs) -> CliResult {
    check_distinct(&[("CAPTURE", &a.capture)], &[("--out", &a.out)])?;
    let input = open_input(&a.capture)?;
    let out = stage_png("--out", &a.out)?;
    let (mut seen, mut wanted) = (0, None);
    let summary = decode_stream(
        a.device,
        input.reader,
        &input.name,
        a.device.default_baud(),
        |scan| {
            if seen == a.revolution {
                wanted = Some(scan);
            }
            seen += 1;
            Ok::<_, CliError>(wanted.is_none())
        },
    )?;
    require_frames(&input.name, a.device, &summary)?;
    let scan = wanted.ok_or_else(|| {
        CliError(format!(
            "{}: revolution {} asked, {seen} decoded",
            input.name, a.revolution
        ))
    })?;
    let title = format!(
        "{} revolution {} of {}",
        a.device,
        a.revolution,
        a.capture.display()
    );
    write_png(out, |path| draw(&scan, &title, path))
}

/// Valid hit points in the sensor frame, drawn as (-y, x) so forward is up and left is left.
fn draw(scan: &DecodedScan, title: &str, out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let rec = &scan.record;
    let points: Vec<(f64, f64)> = (0..rec.beam_count())
        .filter(|&i| rec.valid[i])
        .map(|i| {
            let a = f64::from(rec.start_angle_rad + rec.increment_rad * i as f32);
            let r = f64::from(rec.ranges_m[i]);
            (-r * a.sin(), r * a.cos())
        })
        .collect();
    let extent = points
        .iter()
        .map(|(x, y)| x.abs().max(y.abs()))
        .fold(0.5, f64::max)
        * 1.1;
    let root = BitMapBackend::new(out, (800, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut builder = ChartBuilder::on(&root);
    builder.margin(20);
    if crate::plot::fonts_available() {
        let invalid = rec.valid.iter().filter(|v| !**v).count();
        let rpm = scan
            .rpm
            .map_or("rpm unknown".into(), |r| format!("{r:.0} rpm"));
        builder
            .caption(
                format!(
                    "{title}: {invalid} invalid of {} beams, {rpm}",
                    rec.beam_count()
                ),
                ("sans-serif", 16),
            )
            .x_label_area_size(30)
            .y_label_area_size(40);
    }
    let mut chart = builder.build_cartesian_2d(-extent..extent, -extent..extent)?;
    if crate::plot::fonts_available() {
        chart
            .configure_mesh()
            .x_desc("left ← y (m) → right")
            .y_desc("x forward (m)")
            .draw()?;
    }
    chart.draw_series(points.iter().map(|&p| Circle::new(p, 2, BLUE.filled())))?;
    chart.draw_series(std::iter::once(TriangleMarker::new(
        (0.0, 0.0),
        6,
        RED.filled(),
    )))?;
    root.present()?;
    Ok(())
}
