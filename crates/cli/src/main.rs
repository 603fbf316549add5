//! The `plumbline` command: one module per subcommand, shared reporting in `report`.
use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod lidar_cmd;
mod eval_cmd;
mod log_args;
mod numeric;
mod odometry_cmd;
mod plot;
mod report;
mod sim_closed_loop;
mod sim_cmd;
mod sim_plot;
mod sim_world;

#[derive(Parser)]
#[command(
    name = "plumbline",
    version,
    about = "Indoor lidar navigation and flight control for quadcopters"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Scan-to-scan lidar odometry over a CARMEN log.
    Odometry(odometry_cmd::OdometryArgs),
    /// Score a trajectory against a relations file (Kuemmerle et al. 2009).
    Eval(eval_cmd::EvalArgs),
    /// Lidar devices: decode raw captures, record from a serial port, plot a revolution.
    Lidar(lidar_cmd::LidarArgs),
    /// Fly the simulator: emulated lidar/IMU/sonar logs with exact ground truth.
    Sim(sim_cmd::SimArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: report::CliResult = match cli.command {
        Command::Odometry(args) => odometry_cmd::run(args),
        Command::Eval(args) => eval_cmd::run(args),
        Command::Lidar(args) => lidar_cmd::run(args),
        Command::Sim(args) => sim_cmd::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("plumbline: {e}");
            ExitCode::FAILURE
        }
    }
}
