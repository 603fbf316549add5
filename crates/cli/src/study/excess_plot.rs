//! The energy study's third picture: each setting's hold power above its vehicles' still hover,
//! measured from the integrated energy against what the second-order model predicts from the
//! rotor states, beside the saving the question asks for.

use super::energy::Row;
use super::energy_plot::{canvas, dots, legend, rings, titled};
use plotters::prelude::*;
use plumbline_sim::scenario::Gains;
use std::error::Error;
use std::path::Path;

/// Excesses below this are drawn at it (the log axes need a positive value), W.
const SMALLEST_W: f64 = 1e-3;

fn log10(w: f64) -> f64 {
    w.max(SMALLEST_W).log10()
}

/// Log-log scatter of (measured, predicted) excess per setting that held on every seed, the
/// line where they agree, the defaults ringed, and a dashed line at `target_w` (10 % of the
/// default's hold power: what the question's saving needs the default to waste at least).
pub fn excess(path: &Path, rows: &[Row], target_w: f64) -> Result<(), Box<dyn Error>> {
    let held: Vec<&Row> = rows
        .iter()
        .filter(|r| r.failed == 0 && r.excess.measured_w.is_finite())
        .collect();
    let (lo, hi) = held
        .iter()
        .flat_map(|r| [r.excess.measured_w, r.excess.predicted_w])
        .chain([target_w])
        .fold((f64::MAX, f64::MIN), |(a, b), w| {
            (a.min(log10(w)), b.max(log10(w)))
        });
    let (lo, hi) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    let (root, labels) = canvas(path, (1000, 700))?;
    let mut builder = titled(
        &root,
        labels,
        "Hold power above the still-hover floor: model against measurement (W, log scale)",
        (45, 70),
    );
    let mut chart = builder.build_cartesian_2d(lo..hi, lo..hi)?;
    if labels {
        let power_of_ten = |v: &f64| format!("{}", 10f64.powf(*v));
        chart
            .configure_mesh()
            .x_labels((hi - lo) as usize + 1)
            .y_labels((hi - lo) as usize + 1)
            .x_label_formatter(&power_of_ten)
            .y_label_formatter(&power_of_ten)
            .x_desc("measured excess (W, integrated energy minus the still hover)")
            .y_desc("predicted excess (W, from the rotor states)")
            .draw()?;
    }
    let agree = chart.draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK))?;
    if labels {
        agree
            .label("predicted = measured")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], BLACK));
    }
    let target = chart.draw_series(DashedLineSeries::new(
        [(log10(target_w), lo), (log10(target_w), hi)],
        6,
        4,
        RED.stroke_width(1),
    ))?;
    if labels {
        target
            .label("10 % of the default's hold power")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], RED));
    }
    let at = |r: &Row| (log10(r.excess.measured_w), log10(r.excess.predicted_w));
    dots(&mut chart, &held, labels, at)?;
    // Each controller's default is the first of its settings.
    let defaults = held
        .iter()
        .copied()
        .filter(|r| r.setting.gains == Gains::default());
    rings(&mut chart, defaults, labels, "default tunings", at)?;
    if labels {
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    }
    root.present()?;
    Ok(())
}
