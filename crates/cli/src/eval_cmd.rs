//! `plumbline eval TRAJ RELATIONS`: the relations metric (DESIGN.md §6).

use crate::numeric::{within, Range};
use crate::report::{print_summary, CliError, CliResult};
use clap::Args;
use plumbline_io::eval::{evaluate, DEFAULT_TIME_TOLERANCE_S, LOW_MATCH_RATIO};
use plumbline_io::relations::read_relations;
use plumbline_io::trajectory::read_trajectory;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Trajectory, `timestamp x y theta` per line.
    pub trajectory: PathBuf,
    /// Relations, `t1 t2 x y z roll pitch yaw` per line.
    pub relations: PathBuf,
    /// Largest difference between a relation stamp and a trajectory stamp that still matches, s.
    /// Valid range: [0, 1].
    #[arg(long, default_value_t = DEFAULT_TIME_TOLERANCE_S,
          value_parser = within::<f64>(Range::closed(0.0, 1.0)))]
    pub tolerance: f64,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: EvalArgs) -> CliResult {
    let trajectory = read_trajectory(&args.trajectory)?;
    let relations = read_relations(&args.relations)?;
    let s = evaluate(&trajectory, &relations, args.tolerance).map_err(|e| {
        CliError(format!(
            "{} against {}: {e}",
            args.trajectory.display(),
            args.relations.display()
        ))
    })?;
    if s.on_lost > 0 {
        eprintln!(
            "plumbline: {} of {} relations touch poses the trajectory marks lost (predicted, not measured); they are not scored",
            s.on_lost, s.relations
        );
    }
    let low_match = s.match_ratio < LOW_MATCH_RATIO;
    if low_match {
        eprintln!(
            "plumbline: WARNING: only {} of {} relations ({:.1} %) could be scored; the errors below describe \
             that part of the run only. Is the trajectory from the same log, complete, with stamps copied from it?",
            s.matched,
            s.relations,
            100.0 * s.match_ratio
        );
    } else if s.matched + s.on_lost < s.relations {
        eprintln!(
            "plumbline: {} of {} relations have a timestamp that is not in the trajectory (within {} s); they are not scored",
            s.relations - s.matched - s.on_lost,
            s.relations,
            args.tolerance
        );
    }
    let summary = json!({
        "relations": s.relations,
        "matched": s.matched,
        "match_ratio": s.match_ratio,
        "low_match_ratio": low_match,
        "lost_relations": s.on_lost,
        "trans_mean_m": s.trans_mean_m,
        "trans_std_m": s.trans_std_m,
        "trans2_mean_m2": s.trans2_mean_m2,
        "rot_mean_deg": s.rot_mean_deg,
        "rot_std_deg": s.rot_std_deg,
        "rot2_mean_deg2": s.rot2_mean_deg2,
        "near_relations": s.near_matched,
        "near_trans_mean_m": s.near_trans_mean_m,
        "far_relations": s.far_matched,
        "far_trans_mean_m": s.far_trans_mean_m,
    });
    print_summary(&summary, args.json);
    Ok(())
}
