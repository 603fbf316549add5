//! The map files read back: by a parser of our own, by a reader that follows map_server's
//! loading rules written in Python (when python3 is installed), and as a decoded PNG.

mod common;

use common::room_scan;
use plumbline_core::geom::{Pose2, Vec2};
use plumbline_slam::grid::{CellState, GridConfig, OccupancyGrid, Raster};
use plumbline_slam::map_files::{
    check_writable, write_map, MapPaths, PATH_RGB, PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN, POSE_RGB,
};
use std::path::{Path, PathBuf};

/// A fresh directory under the system temp dir, unique to this test.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("plumbline-map-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 4 m x 3 m room seen from three poses, offset so the map origin is not at zero.
fn room_map() -> (OccupancyGrid, Vec<Pose2>) {
    let mut g = OccupancyGrid::new(GridConfig::default()).unwrap();
    let poses: Vec<Pose2> = [(1.0, 1.0, 0.3), (3.0, 2.0, -1.0), (2.0, 2.5, 2.0)]
        .into_iter()
        .map(|(x, y, t)| Pose2::new(x, y, t))
        .collect();
    for &p in &poses {
        g.insert_scan(p, &room_scan(p, 4.0, 3.0, 720), 10.0)
            .unwrap();
    }
    // Move the whole map by (-2.3, -1.1) m: a rebuild at shifted poses.
    let shifted: Vec<Pose2> = poses
        .iter()
        .map(|p| Pose2::new(p.x - 2.3, p.y - 1.1, p.theta))
        .collect();
    let mut moved = OccupancyGrid::new(GridConfig::default()).unwrap();
    for (p, s) in poses.iter().zip(&shifted) {
        moved
            .insert_scan(*s, &room_scan(*p, 4.0, 3.0, 720), 10.0)
            .unwrap();
    }
    (moved, shifted)
}

/// Splits a binary PGM into (width, height, maxval, pixels), skipping `#` comments.
fn parse_pgm(bytes: &[u8]) -> (usize, usize, usize, Vec<u8>) {
    assert!(bytes.starts_with(b"P5"), "not a binary PGM");
    let mut fields = Vec::new();
    let mut k = 2;
    while fields.len() < 3 {
        while bytes[k].is_ascii_whitespace() {
            k += 1;
        }
        if bytes[k] == b'#' {
            while bytes[k] != b'\n' {
                k += 1;
            }
            continue;
        }
        let start = k;
        while !bytes[k].is_ascii_whitespace() {
            k += 1;
        }
        fields.push(
            std::str::from_utf8(&bytes[start..k])
                .unwrap()
                .parse::<usize>()
                .unwrap(),
        );
    }
    (fields[0], fields[1], fields[2], bytes[k + 1..].to_vec())
}

fn yaml_value<'a>(yaml: &'a str, key: &str) -> &'a str {
    yaml.lines()
        .find_map(|l| l.strip_prefix(&format!("{key}: ")))
        .unwrap_or_else(|| panic!("no `{key}` in\n{yaml}"))
}

#[test]
fn pgm_and_yaml_round_trip() {
    let (grid, path) = room_map();
    let raster = Raster::from_grid(&grid).unwrap().unwrap();
    let dir = temp_dir("round-trip");
    let paths = write_map(&dir.join("room"), &raster, &path).unwrap();
    assert_eq!(paths, MapPaths::of(&dir.join("room")));
    let (w, h, maxval, pixels) = parse_pgm(&std::fs::read(&paths.pgm).unwrap());
    assert_eq!((w, h, maxval), (raster.width, raster.height, 255));
    assert_eq!(pixels.len(), w * h);
    for (k, (&v, s)) in pixels.iter().zip(&raster.states).enumerate() {
        let want = match s {
            CellState::Occupied => PGM_OCCUPIED,
            CellState::Free => PGM_FREE,
            CellState::Unknown => PGM_UNKNOWN,
        };
        assert_eq!(v, want, "pixel {k}");
    }
    let yaml = std::fs::read_to_string(&paths.yaml).unwrap();
    assert_eq!(yaml_value(&yaml, "image"), "\"room.pgm\"");
    assert_eq!(yaml_value(&yaml, "resolution"), "0.05");
    assert_eq!(yaml_value(&yaml, "mode"), "trinary");
    assert_eq!(yaml_value(&yaml, "negate"), "0");
    let origin: Vec<f64> = yaml_value(&yaml, "origin")
        .trim_matches(|c| c == '[' || c == ']')
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    let o = raster.origin_m();
    assert!((origin[0] - o[0]).abs() < 1e-6 && (origin[1] - o[1]).abs() < 1e-6 && origin[2] == 0.0);
    // The map moved by (-2.3, -1.1): its lower-left corner is near (-2.35, -1.15).
    assert!(
        (o[0] + 2.35).abs() < 0.06 && (o[1] + 1.15).abs() < 0.06,
        "{o:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// map_server's loading, in Python: the YAML's fields, the PGM's pixels turned into occupancy
/// by `p = (255 - v) / 255` against the thresholds, rows flipped so row 0 is the bottom, and
/// each occupied cell's centre at `origin + (i + 0.5, j + 0.5) * resolution`.
const MAP_SERVER_READER: &str = r#"
import json, sys, os
yaml_path = sys.argv[1]
meta = {}
for line in open(yaml_path):
    if ':' in line:
        k, v = line.split(':', 1)
        meta[k.strip()] = v.strip()
image = meta['image'].strip('"')
res = float(meta['resolution'])
origin = [float(v) for v in meta['origin'].strip('[]').split(',')]
occ_t, free_t = float(meta['occupied_thresh']), float(meta['free_thresh'])
negate = int(meta['negate'])
assert meta['mode'] == 'trinary'
data = open(os.path.join(os.path.dirname(yaml_path), image), 'rb').read()
fields, k = [], 2
while len(fields) < 3:
    while data[k:k+1].isspace(): k += 1
    if data[k:k+1] == b'#':
        while data[k:k+1] != b'\n': k += 1
        continue
    s = k
    while not data[k:k+1].isspace(): k += 1
    fields.append(int(data[s:k]))
w, h, maxval = fields
pix = data[k+1:]
assert len(pix) == w * h
occupied, free, unknown = [], 0, 0
for row in range(h):
    for col in range(w):
        v = pix[row * w + col]
        p = v / 255.0 if negate else (255 - v) / 255.0
        j = h - row - 1
        if p > occ_t:
            occupied.append([origin[0] + (col + 0.5) * res, origin[1] + (j + 0.5) * res])
        elif p < free_t:
            free += 1
        else:
            unknown += 1
print(json.dumps({'width': w, 'height': h, 'occupied': occupied, 'free': free, 'unknown': unknown}))
"#;

#[test]
fn a_map_server_style_reader_sees_the_grids_cells_where_they_are() {
    let (grid, path) = room_map();
    let raster = Raster::from_grid(&grid).unwrap().unwrap();
    let dir = temp_dir("map-server");
    let paths = write_map(&dir.join("room map"), &raster, &path).unwrap();
    let script = dir.join("reader.py");
    std::fs::write(&script, MAP_SERVER_READER).unwrap();
    let out = match std::process::Command::new("python3")
        .arg(&script)
        .arg(&paths.yaml)
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            println!("skipped: python3 cannot be run ({e})");
            return;
        }
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let count = |key: &str| -> usize {
        let at = text.find(&format!("\"{key}\": ")).unwrap() + key.len() + 4;
        text[at..]
            .split(|c: char| !c.is_ascii_digit())
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    assert_eq!(
        (count("width"), count("height")),
        (raster.width, raster.height)
    );
    let states = |s| raster.states.iter().filter(|&&x| x == s).count();
    assert_eq!(count("free"), states(CellState::Free));
    assert_eq!(count("unknown"), states(CellState::Unknown));
    let list = &text[text.find("\"occupied\": [").unwrap() + 13..text.find("], \"free\"").unwrap()];
    let seen: Vec<Vec2> = list
        .split("], [")
        .map(|pair| {
            let v: Vec<f32> = pair
                .trim_matches(|c| c == '[' || c == ']')
                .split(", ")
                .map(|x| x.parse().unwrap())
                .collect();
            Vec2::new(v[0], v[1])
        })
        .collect();
    let ours: Vec<Vec2> = grid
        .occupied_cells()
        .map(|c| grid.frame().center(c))
        .collect();
    assert_eq!(seen.len(), ours.len());
    for p in &seen {
        assert_eq!(
            grid.state_at(*p),
            CellState::Occupied,
            "map_server puts an occupied cell at {p:?}"
        );
        assert!(
            ours.iter().any(|q| (*q - *p).norm() < 1e-4),
            "{p:?} is not a cell centre"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_picture_is_the_same_raster_with_the_path_on_top() {
    let (grid, path) = room_map();
    let raster = Raster::from_grid(&grid).unwrap().unwrap();
    let dir = temp_dir("png");
    let paths = write_map(&dir.join("room"), &raster, &path).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&paths.png).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).unwrap();
    assert_eq!(
        (info.width as usize, info.height as usize),
        (raster.width, raster.height)
    );
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let at = |(c, r): (i64, i64)| {
        let k = 3 * (r as usize * raster.width + c as usize);
        [rgb[k], rgb[k + 1], rgb[k + 2]]
    };
    // The middle of the first path segment is blue; the last pose carries the green triangle.
    let mid = Vec2::new((path[0].x + path[1].x) / 2.0, (path[0].y + path[1].y) / 2.0);
    assert_eq!(at(raster.pixel_of(mid)), PATH_RGB);
    assert_eq!(at(raster.pixel_of(path[2].translation())), POSE_RGB);
    // Away from the drawing, light is free, dark occupied, grey unknown, as in the PGM.
    let mut checked = [0; 3];
    for row in 0..raster.height {
        for col in 0..raster.width {
            let px = at((col as i64, row as i64));
            if px == PATH_RGB || px == POSE_RGB {
                continue;
            }
            let lum = px[0];
            match raster.state(col, row) {
                CellState::Free => {
                    assert!(lum > 230);
                    checked[0] += 1
                }
                CellState::Occupied => {
                    assert!(lum < 60);
                    checked[1] += 1
                }
                CellState::Unknown => {
                    assert!((100..=200).contains(&lum));
                    checked[2] += 1
                }
            }
        }
    }
    assert!(checked.iter().all(|&n| n > 10), "{checked:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unwritable_prefixes_are_refused_before_any_work() {
    let dir = temp_dir("errors");
    let e = check_writable(&dir.join("no-such-dir/map")).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    let e = check_writable(Path::new("maps/")).unwrap_err();
    assert!(e.to_string().contains("names no file"), "{e}");
    std::fs::create_dir(dir.join("taken.pgm")).unwrap();
    let e = check_writable(&dir.join("taken")).unwrap_err();
    assert!(e.to_string().contains("is a directory"), "{e}");
    std::fs::write(dir.join("file"), b"x").unwrap();
    let e = check_writable(&dir.join("file/map")).unwrap_err();
    assert!(e.to_string().contains("not a directory"), "{e}");
    if Path::new("/proc/self").exists() {
        // Not even root may create files in /proc.
        let e = check_writable(Path::new("/proc/map")).unwrap_err();
        assert!(e.to_string().contains("cannot create files"), "{e}");
    } else {
        println!("skipped the read-only directory case: no /proc here");
    }
    assert!(check_writable(&dir.join("fine")).is_ok());
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        2,
        "the probe file is removed"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
