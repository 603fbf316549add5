//! Plots of a simulated flight: the world from above with the flown path, and altitude,
//! attitude and battery over time.

use crate::plot::fonts_available;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plumbline_sim::runner::{StateSample, TruthPose};
use plumbline_sim::world::World;
use std::error::Error;
use std::path::Path;

/// Walls in black, people's walks in orange, reference dashed grey, flown path in red, scan
/// positions as blue dots.
pub fn top_view(
    path: &Path,
    world: &World,
    states: &[StateSample],
    scans: &[TruthPose],
) -> Result<(), Box<dyn Error>> {
    let root = world_canvas(path, world, 1000)?;
    let mut chart = world_chart(&root, world, "walls and flown path")?;
    for s in &world.walls {
        chart.draw_series(LineSeries::new(
            [(s.a[0], s.a[1]), (s.b[0], s.b[1])],
            BLACK.stroke_width(2),
        ))?;
    }
    let orange = RGBColor(230, 140, 20);
    for p in &world.walkers {
        chart.draw_series(LineSeries::new(
            [(p.from[0], p.from[1]), (p.to[0], p.to[1])],
            orange.stroke_width(3),
        ))?;
    }
    let reference: Vec<(f64, f64)> = states
        .iter()
        .filter_map(|s| s.reference.map(|r| (r.x, r.y)))
        .collect();
    chart.draw_series(LineSeries::new(
        reference,
        RGBColor(160, 160, 160).stroke_width(1),
    ))?;
    chart.draw_series(LineSeries::new(
        states.iter().map(|s| (s.position.x, s.position.y)),
        RED.stroke_width(2),
    ))?;
    chart.draw_series(
        scans
            .iter()
            .map(|t| Circle::new((t.position.x, t.position.y), 2, BLUE.filled())),
    )?;
    root.present()?;
    Ok(())
}

/// A white canvas for the world's floor plan, `width` pixels wide and as high as the plan's
/// shape asks (within 200 pixels and twice the width).
pub fn world_canvas<'p>(
    path: &'p Path,
    world: &World,
    width: u32,
) -> Result<DrawingArea<BitMapBackend<'p>, Shift>, Box<dyn Error>> {
    let [x0, y0, x1, y1] = world.bounds();
    let height = (f64::from(width) * (y1 - y0) / (x1 - x0).max(1e-3)).round() as u32;
    let root = BitMapBackend::new(path, (width, height.clamp(200, 2 * width))).into_drawing_area();
    root.fill(&WHITE)?;
    Ok(root)
}

/// A chart over the world's bounds with half a metre around them, captioned "NAME: `what` (m)"
/// and with axes when a font is available.
pub fn world_chart<'a, 'p>(
    root: &'a DrawingArea<BitMapBackend<'p>, Shift>,
    world: &World,
    what: &str,
) -> Result<WorldChart<'a, 'p>, Box<dyn Error>> {
    let [x0, y0, x1, y1] = world.bounds();
    let labels = fonts_available();
    let mut builder = ChartBuilder::on(root);
    builder.margin(10);
    if labels {
        builder
            .caption(format!("{}: {what} (m)", world.name), ("sans-serif", 20))
            .x_label_area_size(30)
            .y_label_area_size(40);
    }
    let m = 0.5;
    let mut chart = builder.build_cartesian_2d(x0 - m..x1 + m, y0 - m..y1 + m)?;
    if labels {
        chart.configure_mesh().disable_mesh().draw()?;
    }
    Ok(chart)
}

/// The chart [`world_chart`] makes.
pub type WorldChart<'a, 'p> =
    ChartContext<'a, BitMapBackend<'p>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Heading in degrees without the jumps at ±180, so turns read as turns.
fn unwrapped_yaw_deg(states: &[StateSample]) -> Vec<(f64, f64)> {
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    states
        .iter()
        .map(|s| {
            let yaw = s.euler[2];
            if let Some(p) = prev {
                offset -= std::f64::consts::TAU * ((yaw - p) / std::f64::consts::TAU).round();
            }
            prev = Some(yaw);
            (s.t_s, (yaw + offset).to_degrees())
        })
        .collect()
}

/// Three stacked panels: altitude (m), roll/pitch/yaw (deg), battery voltage (V).
pub fn time_series(path: &Path, states: &[StateSample]) -> Result<(), Box<dyn Error>> {
    let series = vec![
        (
            "altitude (m)",
            vec![(
                "z",
                RED,
                states.iter().map(|s| (s.t_s, s.position.z)).collect(),
            )],
        ),
        (
            "attitude (deg)",
            vec![
                (
                    "roll",
                    RED,
                    states
                        .iter()
                        .map(|s| (s.t_s, s.euler[0].to_degrees()))
                        .collect(),
                ),
                (
                    "pitch",
                    GREEN,
                    states
                        .iter()
                        .map(|s| (s.t_s, s.euler[1].to_degrees()))
                        .collect(),
                ),
                ("yaw", BLUE, unwrapped_yaw_deg(states)),
            ],
        ),
        (
            "battery (V)",
            vec![(
                "V",
                BLACK,
                states.iter().map(|s| (s.t_s, s.battery_v)).collect(),
            )],
        ),
    ];
    stacked_panels(path, series)
}

/// One curve of a panel: legend name, colour, (t, value) points.
pub type Line = (&'static str, RGBColor, Vec<(f64, f64)>);

/// Stacked panels sharing the time axis, one per (title, lines).
pub fn stacked_panels(path: &Path, panels: Vec<(&str, Vec<Line>)>) -> Result<(), Box<dyn Error>> {
    let height = 300 * panels.len().max(1) as u32;
    let root = BitMapBackend::new(path, (1200, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    let t_end = panels
        .iter()
        .flat_map(|p| p.1.iter().filter_map(|l| l.2.last().map(|q| q.0)))
        .fold(1e-3, f64::max);
    let labels = fonts_available();
    for (area, (title, lines)) in areas.iter().zip(panels) {
        let (lo, hi) = lines
            .iter()
            .flat_map(|l| l.2.iter().map(|p| p.1))
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
        let (lo, hi) = if lo > hi {
            (0.0, 1.0)
        } else {
            let pad = 0.05 * (hi - lo + 1e-3);
            (lo - pad, hi + pad)
        };
        let mut builder = ChartBuilder::on(area);
        builder.margin(8);
        if labels {
            builder
                .caption(title, ("sans-serif", 16))
                .x_label_area_size(40)
                .y_label_area_size(60);
        }
        let mut chart = builder.build_cartesian_2d(0.0..t_end, lo..hi)?;
        if labels {
            chart.configure_mesh().x_desc("t (s)").draw()?;
        }
        for (name, color, pts) in lines {
            let drawn = chart.draw_series(LineSeries::new(pts, color.stroke_width(1)))?;
            if labels {
                drawn
                    .label(name)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 15, y)], color));
            }
        }
        if labels {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}
