//! Hostile inputs, clear messages: say what is wrong and what to do, up front, before any work;
//! and take in stride what is only unusual (a byte-order mark, gzip under any name).

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::{capture, excerpt, last_json, p, run, scratch, stderr};

const BOM: &[u8] = b"\xEF\xBB\xBF";

fn with_bom(bytes: &[u8]) -> Vec<u8> {
    [BOM, bytes].concat()
}

/// `path` gzip-compressed into `dest`, a name without `.gz`.
fn gzip_to(path: &Path, dest: &Path) {
    let out = Command::new("gzip").arg("-c").arg(path).output().unwrap();
    assert!(out.status.success());
    std::fs::write(dest, out.stdout).unwrap();
}

fn trajectory(log: &Path, out: &Path) -> String {
    let res = run(&["odometry", p(log), "--out", p(out)]);
    assert!(res.status.success(), "{}: {}", log.display(), stderr(&res));
    std::fs::read_to_string(out).unwrap()
}

#[test]
fn a_world_keyword_typo_names_the_keyword_and_the_closest_one() {
    let dir = scratch("world-typo");
    let world = dir.join("typo.world");
    std::fs::write(
        &world,
        "nmae my room\nstart 1 1 0\noutline 0 0 4 0 4 4 0 4\n",
    )
    .unwrap();
    let out = run(&["sim", "--world", p(&world), "--duration", "1"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("line 1"), "{err}");
    assert!(
        err.contains("unknown keyword `nmae`; did you mean `name`?"),
        "{err}"
    );
    assert!(err.contains("start, wall, outline"), "{err}");
}

#[test]
fn a_byte_order_mark_is_invisible_to_every_reader() {
    let dir = scratch("bom");
    let world = dir.join("bom.world");
    let room = "start 1 1 0\naltitude 1\noutline 0 0 6 0 6 4.5 0 4.5\npath 1 1 4 1\n";
    std::fs::write(&world, with_bom(room.as_bytes())).unwrap();
    let out = support::fly(&world, None);
    assert!(out.status.success(), "{}", stderr(&out));

    let plain = trajectory(&excerpt(), &dir.join("plain.traj"));
    let log = dir.join("bom.clf");
    std::fs::write(&log, with_bom(&std::fs::read(excerpt()).unwrap())).unwrap();
    let bom = trajectory(&log, &dir.join("bom.traj"));
    assert_eq!(bom, plain, "the first scan was dropped or changed");

    let traj = dir.join("bom-traj.txt");
    std::fs::write(&traj, with_bom(plain.as_bytes())).unwrap();
    let relations = Path::new(support::REPO).join("data/intel-excerpt.relations");
    let out = run(&["eval", p(&traj), p(&relations), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(last_json(&out)["matched"].as_u64().unwrap() > 0);
}

#[test]
fn gzip_is_recognised_by_content_whatever_the_name() {
    let dir = scratch("gzip");
    let plain = trajectory(&excerpt(), &dir.join("plain.traj"));
    let log = dir.join("compressed.clf");
    gzip_to(&excerpt(), &log);
    assert_eq!(trajectory(&log, &dir.join("gz.traj")), plain);

    let relations = Path::new(support::REPO).join("data/intel-excerpt.relations");
    let gz_relations = dir.join("compressed.relations");
    gzip_to(&relations, &gz_relations);
    let traj = dir.join("plain.traj");
    let a = run(&["eval", p(&traj), p(&relations), "--json"]);
    let b = run(&["eval", p(&traj), p(&gz_relations), "--json"]);
    assert!(b.status.success(), "{}", stderr(&b));
    assert_eq!(last_json(&a), last_json(&b));

    let room = dir.join("room.txt");
    std::fs::write(
        &room,
        "start 1 1 0\noutline 0 0 6 0 6 4.5 0 4.5\npath 1 1 4 1\n",
    )
    .unwrap();
    let world = dir.join("room.world");
    gzip_to(&room, &world);
    let out = support::fly(&world, None);
    assert!(out.status.success(), "{}", stderr(&out));

    let cap = dir.join("capture.bin");
    gzip_to(&capture(), &cap);
    let a = run(&[
        "lidar",
        "decode",
        "--device",
        "xv11",
        p(&capture()),
        "--json",
    ]);
    let b = run(&["lidar", "decode", "--device", "xv11", p(&cap), "--json"]);
    assert!(b.status.success(), "{}", stderr(&b));
    assert_eq!(last_json(&a)["packets_ok"], last_json(&b)["packets_ok"]);
}

#[test]
fn a_plot_name_without_png_is_refused_before_any_work() {
    let dir = scratch("plot-name");
    let traj = dir.join("t.traj");
    let out = run(&[
        "odometry",
        p(&excerpt()),
        "--out",
        p(&traj),
        "--plot",
        p(&dir.join("t.jpg")),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("plots are written as PNG; give a file name ending in .png"),
        "{}",
        stderr(&out)
    );
    assert!(
        !traj.exists(),
        "the work was done before the name was checked"
    );
    let out = run(&[
        "lidar",
        "plot",
        "--device",
        "xv11",
        p(&capture()),
        "--out",
        p(&dir.join("rev")),
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("ending in .png"), "{}", stderr(&out));
    assert_eq!(support::entries(&dir), Vec::<String>::new());
}

/// A path that cannot be created: its directory would have to be inside a regular file.
fn unwritable(dir: &Path, name: &str) -> PathBuf {
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    file.join(name)
}

#[test]
fn an_output_that_cannot_be_created_is_reported_before_the_work() {
    let dir = scratch("unwritable");
    let traj = dir.join("t.traj");
    let bad_plot = unwritable(&dir, "t.png");
    let out = run(&[
        "odometry",
        p(&excerpt()),
        "--out",
        p(&traj),
        "--plot",
        p(&bad_plot),
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains(p(&bad_plot)), "{}", stderr(&out));
    assert!(
        !traj.exists(),
        "the work was done before the plot was found unwritable"
    );

    let bad_log = unwritable(&dir, "x.log");
    let out = run(&[
        "lidar",
        "decode",
        "--device",
        "xv11",
        p(&capture()),
        "--out",
        p(&bad_log),
        "--json",
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains(p(&bad_log)), "{}", stderr(&out));
    assert!(
        out.stdout.is_empty(),
        "decoded before the output was checked"
    );
}
