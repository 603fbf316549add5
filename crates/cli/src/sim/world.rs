//! Worlds for `plumbline sim` that come from files other than the world format: occupancy
//! images (PGM plus a map_server YAML) and CARMEN logs with poses, rasterised.

use crate::report::CliError;
use plumbline_io::carmen::{CarmenLog, OdomPose};
use plumbline_io::output;
use plumbline_sim::world::occupancy::Occupancy;
use plumbline_sim::world::scene::Scene;
use plumbline_sim::world::World;
use std::path::Path;

/// Resolution of worlds rasterised from logs, m per cell.
pub const RASTER_RESOLUTION_M: f64 = 0.1;
/// Laser hits a cell needs to count as wall (one stray hit is noise or a passer-by).
const RASTER_MIN_HITS: u32 = 2;
/// Hits beyond this range are too sparse to outline walls, m.
const RASTER_MAX_RANGE_M: f32 = 15.0;
/// Longest straight leg of a rasterised survey path, m.
const MAX_LEG_M: f64 = 4.0;
/// Waypoints closer than this to a wall are dropped, m (a 450-class drone is 0.35 m in radius).
const WAYPOINT_CLEARANCE_M: f64 = 0.55;

/// `resolution` and `origin` from a map_server YAML (the only keys the world needs).
fn read_map_yaml(path: &Path) -> Result<(f64, [f64; 2]), CliError> {
    let name = path.display();
    let text = plumbline_io::input::read_text(path)
        .map_err(|e| CliError(format!("{e} (a PGM world needs its map_server YAML)")))?;
    let mut resolution = None;
    let mut origin = None;
    for line in text.lines() {
        let Some((key, value)) = line.split_once(':') else {
            continue;
        };
        match key.trim() {
            "resolution" => resolution = value.trim().parse::<f64>().ok(),
            "origin" => {
                let v: Vec<f64> = value
                    .trim()
                    .trim_matches(['[', ']'])
                    .split(',')
                    .filter_map(|s| s.trim().parse().ok())
                    .collect();
                origin = (v.len() >= 2).then(|| [v[0], v[1]]);
            }
            _ => {}
        }
    }
    match (resolution, origin) {
        (Some(r), Some(o)) => Ok((r, o)),
        _ => Err(CliError(format!(
            "{name}: needs `resolution:` and `origin: [x, y, yaw]`"
        ))),
    }
}

/// A world from `map.pgm` and its `map.yaml`; it starts at the most open point and has no
/// survey path (fly `--scenario hold`).
pub fn load_pgm(path: &Path) -> Result<World, CliError> {
    let (resolution, origin) = read_map_yaml(&path.with_extension("yaml"))?;
    let bytes = std::fs::read(path).map_err(|e| CliError(format!("{}: {e}", path.display())))?;
    let grid = Occupancy::from_pgm(&bytes, resolution, origin)
        .map_err(|e| CliError(format!("{}: {e}", path.display())))?;
    let name = path
        .file_stem()
        .map_or("image".into(), |s| s.to_string_lossy().into_owned());
    let mut world = World::from_occupancy(&name, &grid, [0.0; 3], Vec::new(), 1.0, 2.5);
    if world.walls.is_empty() {
        return Err(CliError(format!(
            "{}: the image has no occupied cells",
            path.display()
        )));
    }
    let p = world.most_open_point();
    world.start = [p[0], p[1], 0.0];
    Ok(world)
}

/// Rasterises a log's laser hits at its stored poses into a world; the survey path follows
/// the logged trajectory. Returns the world and its occupancy grid (for a PGM copy).
pub fn rasterize(
    log: &CarmenLog,
    log_name: &str,
    name: &str,
) -> Result<(World, Occupancy), CliError> {
    let mut hits = Vec::new();
    let mut poses = Vec::new();
    for rec in &log.scans {
        let Some(p) = rec.odom else { continue };
        poses.push(p);
        let (s, c) = p.theta_rad.sin_cos();
        for (i, (&r, &ok)) in rec.ranges_m.iter().zip(&rec.valid).enumerate() {
            if ok && r < RASTER_MAX_RANGE_M {
                let a = (rec.start_angle_rad + rec.increment_rad * i as f32) as f64;
                let (lx, ly) = (r as f64 * a.cos(), r as f64 * a.sin());
                hits.push([p.x_m + c * lx - s * ly, p.y_m + s * lx + c * ly]);
            }
        }
    }
    let first = poses
        .first()
        .ok_or_else(|| CliError("the log has no scans with poses".into()))?;
    let grid = Occupancy::from_hits(&hits, RASTER_RESOLUTION_M, RASTER_MIN_HITS).map_err(|e| {
        match farthest_pose(log) {
            Some((line, p)) => CliError(format!(
                "{log_name}:{line}: {e}; the pose farthest from the others is here ({}, {}): fix or remove it",
                p.x_m, p.y_m
            )),
            None => CliError(format!("{log_name}: {e}")),
        }
    })?;
    let mut world = World::from_occupancy(
        name,
        &grid,
        [first.x_m, first.y_m, first.theta_rad],
        Vec::new(),
        1.0,
        2.5,
    );
    world.path = drone_path(&Scene::new(&world), &poses);
    if let Some(p) = world.path.first() {
        world.start = [p[0], p[1], first.theta_rad];
    }
    Ok((world, grid))
}

/// The line and pose of the scan whose pose lies farthest from the median pose: where a log
/// whose hits span an absurd extent went wrong (a corrupt or unit-mixed pose).
fn farthest_pose(log: &CarmenLog) -> Option<(usize, OdomPose)> {
    let poses: Vec<(usize, OdomPose)> = log
        .scans
        .iter()
        .zip(&log.scan_lines)
        .filter_map(|(rec, &line)| rec.odom.map(|p| (line, p)))
        .collect();
    let median = |f: fn(&OdomPose) -> f64| {
        let mut v: Vec<f64> = poses.iter().map(|(_, p)| f(p)).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    let (mx, my) = (median(|p| p.x_m)?, median(|p| p.y_m)?);
    poses.into_iter().max_by(|a, b| {
        let d = |p: &OdomPose| (p.x_m - mx).hypot(p.y_m - my);
        d(&a.1).total_cmp(&d(&b.1))
    })
}

/// The logged trajectory straightened into waypoints a drone can fly: a wheeled robot brushes
/// past furniture that propellers would hit, so poses too close to a wall are skipped, and
/// consecutive poses are merged while the straight line between waypoints keeps its distance
/// from every wall.
fn drone_path(scene: &Scene, poses: &[plumbline_io::carmen::OdomPose]) -> Vec<[f64; 2]> {
    let roomy = |p: [f64; 2]| scene.clearance(p, 1.0) >= WAYPOINT_CLEARANCE_M;
    let line_clear = |a: [f64; 2], b: [f64; 2]| {
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.1).ceil().max(1.0) as usize;
        (0..=n).all(|k| {
            let u = k as f64 / n as f64;
            roomy([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])])
        })
    };
    let mut free = poses.iter().map(|p| [p.x_m, p.y_m]).filter(|p| roomy(*p));
    let Some(first) = free.next() else {
        return Vec::new();
    };
    let mut path = vec![first];
    let mut candidate: Option<[f64; 2]> = None;
    for p in free {
        let last = path[path.len() - 1];
        if (p[0] - last[0]).hypot(p[1] - last[1]) <= MAX_LEG_M && line_clear(last, p) {
            candidate = Some(p);
            continue;
        }
        // Out of reach: fix the last reachable pose as a waypoint; poses that cannot be
        // reached from it are passed over until the robot comes back into view.
        if let Some(c) = candidate.take() {
            path.push(c);
            if line_clear(c, p) && (p[0] - c[0]).hypot(p[1] - c[1]) <= MAX_LEG_M {
                candidate = Some(p);
            }
        }
    }
    path.extend(candidate);
    path
}

/// Writes `NAME.world`, `NAME.pgm` and `NAME.yaml` into `dir`.
pub fn write_world(dir: &Path, world: &World, grid: &Occupancy) -> Result<(), CliError> {
    let write = |ext: &str, bytes: &[u8]| {
        let path = dir.join(format!("{}.{ext}", world.name));
        output::write(&path, bytes).map_err(CliError::from)
    };
    write("world", world.to_text().as_bytes())?;
    write("pgm", &grid.to_pgm())?;
    let yaml = format!(
        "image: {}.pgm\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        world.name, grid.resolution_m, grid.origin[0], grid.origin[1]
    );
    write("yaml", yaml.as_bytes())
}
