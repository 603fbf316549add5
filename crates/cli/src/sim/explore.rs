//! The exploring side of `plumbline sim`: what an exploration is scored on in the summary, the
//! companion's map with the flown path over the true walls (`map.png`), and the explored share
//! of the reachable area over time (`explored.png`).

use super::outputs::create;
use super::plot::{stacked_panels, world_canvas, world_chart, Line};
use crate::plot::write_png;
use crate::report::CliError;
use plotters::coord::ReverseCoordTranslate;
use plotters::prelude::*;
use plumbline_core::geom::Vec2;
use plumbline_explore::DoneReason;
use plumbline_sim::runner::companion::ExploreEnd;
use plumbline_sim::runner::{SimConfig, StateSample};
use plumbline_sim::scenario::explore_score::{Exploration, ExploreScore};
use plumbline_slam::grid::CellState;
use serde_json::{json, Value};
use std::error::Error;
use std::path::Path;

fn end_name(end: ExploreEnd) -> &'static str {
    match end {
        ExploreEnd::Explorer(DoneReason::NoReachableFrontier) => "no_reachable_frontier",
        ExploreEnd::Explorer(DoneReason::CoverageStalled) => "coverage_stalled",
        ExploreEnd::TimeBudget => "time_budget",
        ExploreEnd::BlindBudget => "blind_budget",
    }
}

/// Adds the exploration's figures to `summary`; `min_clearance_m` becomes the exploration's,
/// which counts the people as well as the walls.
pub fn extend_summary(summary: &mut Value, score: &ExploreScore, exploration: &Exploration) {
    let c = &exploration.companion;
    let extra = json!({
        "guidance": score.strategy.name(),
        "explored_fraction": score.explored_fraction,
        "reachable_area_m2": score.reachable_area_m2,
        "time_to_90pct_s": score.time_to_90pct_s,
        "collisions": score.collisions,
        "min_clearance_m": score.min_clearance_m,
        "returned_home": score.returned_home,
        "home_error_m": score.home_error_m,
        "landed": score.landed,
        "map_error_m": score.map_error_m,
        "explore_end_s": score.explore_end.map(|e| e.0),
        "explore_end": score.explore_end.map(|e| end_name(e.1)),
        "path_home_m": c.path_home_m,
        "return_stall_replans": c.stall_replans,
        "return_given_up_s": c.gave_up_s,
        "landed_off_home": c.landed_off_home,
        "slam_predicted_scans": c.predicted,
        "slam_degenerate_s": c.degenerate_s,
        "map_corrections": c.resets,
    });
    if let (Some(map), Value::Object(extra)) = (summary.as_object_mut(), extra) {
        map.extend(extra);
    }
}

/// `map.png` and `explored.png`.
pub fn plots(
    dir: &Path,
    config: &SimConfig,
    exploration: &Exploration,
    states: &[StateSample],
) -> Result<(), CliError> {
    write_png(create(dir, "map.png")?, |p| {
        map_view(p, config, exploration, states)
    })?;
    let explored: Vec<(f64, f64)> = exploration
        .explored
        .iter()
        .map(|&(t, f)| (t, 100.0 * f))
        .collect();
    let line: Line = ("seen", BLUE, explored);
    write_png(create(dir, "explored.png")?, |p| {
        stacked_panels(p, vec![("reachable area seen (%)", vec![line])])
    })
}

/// The companion's map in the world frame (free cells light, occupied dark), the true walls
/// in red over it, and the flown path in blue from take-off (green) to the end (black).
fn map_view(
    path: &Path,
    config: &SimConfig,
    exploration: &Exploration,
    states: &[StateSample],
) -> Result<(), Box<dyn Error>> {
    let world = &config.world;
    let root = world_canvas(path, world, 1200)?;
    let mut chart = world_chart(&root, world, "the vehicle's map, flown path, true walls")?;
    // Each pixel shows the map cell under it, so the map is drawn whole at any scale.
    let map = &exploration.map;
    let [mx, my, myaw] = exploration.map_in_world;
    let (s, c) = myaw.sin_cos();
    let free = RGBColor(205, 225, 245);
    let occupied = RGBColor(60, 60, 60);
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    for py in ys {
        for px in xs.clone() {
            let Some((x, y)) = chart.as_coord_spec().reverse_translate((px, py)) else {
                continue;
            };
            let (dx, dy) = (x - mx, y - my);
            let in_map = Vec2::new((c * dx + s * dy) as f32, (-s * dx + c * dy) as f32);
            let color = match map.state_at(in_map) {
                CellState::Free => free,
                CellState::Occupied => occupied,
                CellState::Unknown => continue,
            };
            root.draw_pixel((px, py), &color)?;
        }
    }
    for seg in &world.walls {
        chart.draw_series(LineSeries::new(
            [(seg.a[0], seg.a[1]), (seg.b[0], seg.b[1])],
            RED.stroke_width(1),
        ))?;
    }
    chart.draw_series(LineSeries::new(
        states.iter().map(|s| (s.position.x, s.position.y)),
        BLUE.stroke_width(2),
    ))?;
    let ends = [
        (states.first(), GREEN.filled()),
        (states.last(), BLACK.filled()),
    ];
    for (s, style) in ends {
        if let Some(s) = s {
            chart.draw_series([Circle::new((s.position.x, s.position.y), 5, style)])?;
        }
    }
    root.present()?;
    Ok(())
}
