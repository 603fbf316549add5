//! The energy study's two pictures: energy per minute against RMS hold error with the Pareto
//! front, and the power breakdown beside seed 000 Fig. 12(a).

use super::energy::Row;
use crate::plot::fonts_available;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plumbline_sim::scenario::Controller;
use std::error::Error;
use std::path::Path;

/// Seed 000 Fig. 12(a): motors 95 %, ESCs 4 %, flight controller 1 % of the measured power.
const SEED_000_FIG_12A: [f64; 3] = [0.95, 0.04, 0.01];

fn color(c: Controller) -> RGBColor {
    match c {
        Controller::Mrac => RGBColor(200, 90, 20),
        _ => RGBColor(40, 90, 200),
    }
}

/// Every setting as a dot (colour by controller), the front joined in black, the default as a
/// red ring and the still-hover floor as a dashed line.
pub fn pareto(
    path: &Path,
    rows: &[Row],
    front: &[usize],
    floor_wh_min: f64,
) -> Result<(), Box<dyn Error>> {
    let held: Vec<&Row> = rows
        .iter()
        .filter(|r| r.point.error_m.is_finite())
        .collect();
    let fold = |f: fn(&Row) -> f64| {
        held.iter()
            .map(|r| f(r))
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)))
    };
    let (e0, e1) = fold(|r| r.point.error_m);
    let (w0, w1) = fold(|r| r.point.energy_wh_min);
    let (e0, e1) = if e0 > e1 { (0.0, 1.0) } else { (0.0, e1 * 1.1) };
    let (w0, w1) = if w0 > w1 {
        (floor_wh_min, floor_wh_min * 1.1)
    } else {
        let lo = w0.min(floor_wh_min);
        let pad = 0.1 * (w1 - lo).max(1e-4);
        (lo - pad, w1 + pad)
    };
    let (root, labels) = canvas(path, (1000, 700))?;
    let mut builder = titled(
        &root,
        labels,
        "Energy per minute of hold against RMS hold error (room, mean over seeds)",
        (45, 70),
    );
    let mut chart = builder.build_cartesian_2d(e0..e1, w0..w1)?;
    if labels {
        chart
            .configure_mesh()
            .x_desc("RMS hold error (m)")
            .y_desc("energy (Wh/min)")
            .draw()?;
    }
    let floor = chart.draw_series(DashedLineSeries::new(
        [(e0, floor_wh_min), (e1, floor_wh_min)],
        6,
        4,
        BLACK.stroke_width(1),
    ))?;
    if labels {
        floor
            .label("still hover of the flown vehicles (the floor)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], BLACK));
    }
    dots(&mut chart, &held, labels, |r| {
        (r.point.error_m, r.point.energy_wh_min)
    })?;
    let line: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| (rows[i].point.error_m, rows[i].point.energy_wh_min))
        .collect();
    let drawn = chart.draw_series(LineSeries::new(line, BLACK.stroke_width(2)))?;
    if labels {
        drawn
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], BLACK.stroke_width(2)));
    }
    let default = rows.first().filter(|r| r.point.error_m.is_finite());
    rings(&mut chart, default, labels, "default tuning", |r| {
        (r.point.error_m, r.point.energy_wh_min)
    })?;
    if labels {
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    root.present()?;
    Ok(())
}

/// Fractions of the power (motors, ESCs, avionics) as grouped bars: seed 000 Fig. 12(a), the
/// default tuning, and the front's lowest-energy setting.
pub fn breakdown(path: &Path, default: &Row, lowest: Option<&Row>) -> Result<(), Box<dyn Error>> {
    let fractions = |r: &Row| {
        let total: f64 = r.parts_wh_min.iter().sum();
        r.parts_wh_min.map(|p| p / total.max(1e-12))
    };
    let mut groups = vec![
        ("seed 000 Fig. 12(a)", SEED_000_FIG_12A),
        ("simulated, default tuning", fractions(default)),
    ];
    if let Some(r) = lowest {
        groups.push(("simulated, lowest-energy setting", fractions(r)));
    }
    let (root, labels) = canvas(path, (1000, 600))?;
    let mut builder = titled(
        &root,
        labels,
        "Power breakdown: motors, ESCs, avionics (fraction of total)",
        (40, 60),
    );
    let parts = ["motors", "ESCs", "avionics"];
    let mut chart = builder.build_cartesian_2d(0.0..3.0f64, 0.0..1.0f64)?;
    if labels {
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(3)
            .x_label_formatter(&|x| {
                let i = x.floor() as usize;
                parts.get(i).map_or(String::new(), |s| s.to_string())
            })
            .y_desc("fraction of power")
            .draw()?;
    }
    let colors = [
        RGBColor(120, 120, 120),
        RGBColor(40, 90, 200),
        RGBColor(200, 90, 20),
    ];
    let width = 0.8 / groups.len() as f64;
    for (g, ((name, f), col)) in groups.iter().zip(colors).enumerate() {
        let bars = (0..3).map(move |i| {
            let x = i as f64 + 0.1 + g as f64 * width;
            Rectangle::new([(x, 0.0), (x + width * 0.9, f[i])], col.filled())
        });
        let drawn = chart.draw_series(bars)?;
        if labels {
            let text = format!(
                "{name}: {:.1} / {:.1} / {:.1} %",
                100.0 * f[0],
                100.0 * f[1],
                100.0 * f[2]
            );
            drawn
                .label(text)
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], col.filled()));
        }
    }
    if labels {
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    root.present()?;
    Ok(())
}

pub(super) type Chart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The series labels in the `corner` where the data leave room, on a light box.
pub(super) fn legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    corner: SeriesLabelPosition,
) -> Result<(), Box<dyn Error>> {
    chart
        .configure_series_labels()
        .position(corner)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// A white picture of `size` pixels at `path`, and whether text can be drawn on it.
pub(super) fn canvas(
    path: &Path,
    size: (u32, u32),
) -> Result<(DrawingArea<BitMapBackend<'_>, Shift>, bool), Box<dyn Error>> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    Ok((root, fonts_available()))
}

/// Each controller's `rows` as dots at `at(row)`, in its colour, labelled by its name.
pub(super) fn dots<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    rows: &[&Row],
    labels: bool,
    at: impl Fn(&Row) -> (f64, f64),
) -> Result<(), Box<dyn Error>> {
    for c in [Controller::Pid, Controller::Mrac] {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.setting.controller == c)
            .map(|r| at(r))
            .collect();
        if pts.is_empty() {
            continue;
        }
        let col = color(c);
        let drawn = chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, col.filled())))?;
        if labels {
            drawn
                .label(c.name())
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, col.filled()));
        }
    }
    Ok(())
}

/// Red rings around `rows` at `at(row)`, labelled `what`.
pub(super) fn rings<'a, 'b: 'a, 'r>(
    chart: &mut Chart<'a, 'b>,
    rows: impl IntoIterator<Item = &'r Row>,
    labels: bool,
    what: &str,
    at: impl Fn(&Row) -> (f64, f64),
) -> Result<(), Box<dyn Error>> {
    let drawn = chart.draw_series(
        rows.into_iter()
            .map(|r| Circle::new(at(r), 9, RED.stroke_width(2))),
    )?;
    if labels {
        drawn
            .label(what)
            .legend(|(x, y)| Circle::new((x + 7, y), 6, RED.stroke_width(2)));
    }
    Ok(())
}

/// The study charts' builder on `root`: their margin and, when text can be drawn (`labels`),
/// the caption and room for the (x, y) axis labels; without fonts the plot keeps the space.
pub(super) fn titled<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    labels: bool,
    caption: &str,
    (x_area, y_area): (u32, u32),
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(root);
    builder.margin(15);
    if labels {
        builder
            .caption(caption, ("sans-serif", 20))
            .x_label_area_size(x_area)
            .y_label_area_size(y_area);
    }
    builder
}
