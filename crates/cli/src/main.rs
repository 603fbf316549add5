//! The `plumbline` command: one module per subcommand, shared reporting in `report`.
use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod plot;
mod report;

#[derive(Parser)]
#[command(name = "plumbline", version, about = "Indoor lidar navigation and flight control for quadcopters")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: report::CliResult = match cli.command {};
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("plumbline: {e}");
            ExitCode::FAILURE
        }
    }
}
