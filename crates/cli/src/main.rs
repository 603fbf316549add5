//! The `plumbline` command: one module per subcommand, shared reporting in `report`.
use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod companion_cmd;
mod eval_cmd;
mod lidar_cmd;
mod log_args;
mod numeric;
mod odometry_cmd;
mod plot;
mod report;
mod sim;
mod slam_cmd;
mod study;
mod view_args;
mod view_feed;

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
    /// Lidar SLAM over a CARMEN log: trajectory, pose graph and map.
    Slam(slam_cmd::SlamArgs),
    /// Score a trajectory against a relations file (Kuemmerle et al. 2009).
    Eval(eval_cmd::EvalArgs),
    /// Lidar devices: decode raw captures, record from a serial port, plot a revolution.
    Lidar(lidar_cmd::LidarArgs),
    /// Companion computer: lidar SLAM poses and obstacles to a PX4 or ArduPilot autopilot
    /// over MAVLink.
    Companion(companion_cmd::CompanionArgs),
    /// Fly the simulator: emulated lidar/IMU/sonar logs with exact ground truth.
    Sim(Box<sim::SimArgs>),
    /// Studies that fly many simulated runs and answer with a table and plots.
    Study(study::StudyArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: report::CliResult = match cli.command {
        Command::Odometry(args) => odometry_cmd::run(args),
        Command::Slam(args) => slam_cmd::run(args),
        Command::Eval(args) => eval_cmd::run(args),
        Command::Lidar(args) => lidar_cmd::run(args),
        Command::Companion(args) => companion_cmd::run(args),
        Command::Sim(args) => sim::run(*args),
        Command::Study(args) => study::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("plumbline: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;
    use std::any::TypeId;

    /// Integer options for which every value the type holds means something (a seed, an index
    /// checked against what was decoded).
    const ANY_VALUE_IS_VALID: &[&str] = &["seed", "revolution"];

    /// Every numeric option of every subcommand, present and future, documents a valid range
    /// (and so goes through `numeric::within`, which prints the same range in its errors).
    #[test]
    fn every_numeric_option_documents_its_valid_range() {
        let numeric = [
            TypeId::of::<f32>(),
            TypeId::of::<f64>(),
            TypeId::of::<u16>(),
            TypeId::of::<u32>(),
            TypeId::of::<u64>(),
            TypeId::of::<usize>(),
            TypeId::of::<i32>(),
            TypeId::of::<i64>(),
        ];
        let mut stack = vec![(String::from("plumbline"), Cli::command())];
        let mut checked = 0;
        while let Some((path, cmd)) = stack.pop() {
            for arg in cmd.get_arguments() {
                let id = arg.get_value_parser().type_id();
                if !numeric.iter().any(|t| id == *t)
                    || ANY_VALUE_IS_VALID.contains(&arg.get_id().as_str())
                {
                    continue;
                }
                let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
                assert!(
                    help.contains("Valid range: "),
                    "{path} --{}: no `Valid range:` in its help",
                    arg.get_id()
                );
                checked += 1;
            }
            for sub in cmd.get_subcommands() {
                stack.push((format!("{path} {}", sub.get_name()), sub.clone()));
            }
        }
        assert!(checked >= 16, "only {checked} numeric options found");
    }
}
