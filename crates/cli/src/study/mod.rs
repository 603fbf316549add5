//! `plumbline study`: experiments that fly or replay many runs and answer a question with a
//! table and plots, each reproduced by one command.

mod energy;
mod energy_plot;
mod energy_table;
mod excess_plot;
mod paper;
mod pareto;

use crate::report::CliResult;
use clap::{Args, Subcommand};

#[derive(Args, Debug)]
pub struct StudyArgs {
    #[command(subcommand)]
    pub study: Study,
}

#[derive(Subcommand, Debug)]
pub enum Study {
    /// Energy per minute against hold error over a sweep of the position-loop gains and the
    /// tilt command filter, with the Pareto front and the power breakdown (seed 000 sec. 5.3).
    Energy(energy::EnergyArgs),
    /// Seed 000 Fig. 5 (ICP against ICL drift over a room flight) and Fig. 7 (a still lidar,
    /// a person walking past, with and without rejection), the paper's method beside
    /// Plumbline's.
    Paper(paper::PaperArgs),
}

pub fn run(args: StudyArgs) -> CliResult {
    match args.study {
        Study::Energy(a) => energy::run(a),
        Study::Paper(a) => paper::run(a),
    }
}
