//! Scoring a map against the simulated world it was made in.

use crate::report::CliError;
use crate::sim::load_world;
use plumbline_io::trajectory::read_trajectory;
use plumbline_sim::map_error::{grid_map_error, MapError};
use plumbline_sim::world::World;
use plumbline_slam::grid::OccupancyGrid;
use std::path::Path;

pub struct Truth {
    world: World,
    /// (time, pose) rows of the simulator's truth.txt.
    poses: Vec<(f64, [f64; 3])>,
}

impl Truth {
    pub fn load(world: &str, truth: &Path) -> Result<Self, CliError> {
        let world = load_world(world)?;
        let poses = read_trajectory(truth)?
            .into_iter()
            .map(|t| (t.timestamp_s, [t.pose.x_m, t.pose.y_m, t.pose.theta_rad]))
            .collect::<Vec<_>>();
        if poses.is_empty() {
            return Err(CliError(format!("{}: no poses", truth.display())));
        }
        Ok(Self { world, poses })
    }

    /// The map error of `grid`, whose frame is the pose of the log's first scan.
    pub fn map_error(
        &self,
        grid: &OccupancyGrid,
        first_scan_s: f64,
    ) -> Result<Option<MapError>, CliError> {
        let t = first_scan_s;
        let &(stamp, start) = self
            .poses
            .iter()
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .expect("truth has poses");
        if (stamp - t).abs() > 1e-3 {
            return Err(CliError(format!(
                "the truth file has no pose at the log's first scan ({t} s; nearest {stamp} s): is it the same run?"
            )));
        }
        Ok(grid_map_error(grid, &self.world, start))
    }
}
