//! Loop closure on a path retraced in the opposite direction with a 180° lidar: the new
//! keyframe faces away from everything the old keyframe at the same place saw, so the revisit
//! must be proposed whatever the heading and verified against the keyframes the old path
//! passed on its way there, not the candidate's own scan. Also the back end's other
//! scan-to-scan edges: a keyframe matched directly against the one two before it.

use plumbline_core::geom::{Pose2, Vec2};
use plumbline_core::scan::{Beam, Scan};
use plumbline_slam::backend::Backend;
use plumbline_slam::keyframe::Keyframe;
use plumbline_slam::loops::LoopCloser;
use plumbline_slam::{LoopConfig, SlamConfig};

/// A room 8 m x 6 m.
fn walls() -> Vec<(Vec2, Vec2)> {
    let corners = [(0.0, 0.0), (8.0, 0.0), (8.0, 6.0), (0.0, 6.0)].map(|(x, y)| Vec2::new(x, y));
    (0..4).map(|k| (corners[k], corners[(k + 1) % 4])).collect()
}

const MAX_RANGE_M: f32 = 4.0;

/// A 181-beam, 180° scan from `pose`: exact ranges to the nearest wall, none beyond 4 m.
fn scan(pose: Pose2, walls: &[(Vec2, Vec2)]) -> Scan<181> {
    let mut scan = Scan::new(0.0);
    for k in 0..181 {
        let a = (k as f32 - 90.0).to_radians();
        let d = Vec2::new((pose.theta + a).cos(), (pose.theta + a).sin());
        let range = walls
            .iter()
            .filter_map(|&(p, q)| ray_hits(pose.translation(), d, p, q))
            .fold(f32::INFINITY, f32::min);
        let beam = if range <= MAX_RANGE_M {
            Beam::new(a, range)
        } else {
            Beam::invalid(a)
        };
        scan.push(beam).unwrap();
    }
    scan
}

/// Distance along the ray `o + t d` to the segment `p q`, if it hits it.
fn ray_hits(o: Vec2, d: Vec2, p: Vec2, q: Vec2) -> Option<f32> {
    let e = q - p;
    let denom = d.cross(e);
    if denom.abs() < 1e-9 {
        return None;
    }
    let t = (p - o).cross(e) / denom;
    let u = (p - o).cross(d) / denom;
    (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

/// South along x = 2 m from y = 5 m, then east along y = 1.5 m to x = 7 m, then back west,
/// a keyframe every 0.25 m; the way back is tracked with a drift of 0.25 m, -0.1 m and 2.3°
/// (what the graph believes). Returns the keyframes, their graph poses and the truth.
fn out_and_back() -> (Vec<Keyframe>, Vec<Pose2>, Vec<Pose2>) {
    use core::f32::consts::{FRAC_PI_2, PI};
    let walls = walls();
    let south = (0..14).map(|k| Pose2::new(2.0, 5.0 - 0.25 * k as f32, -FRAC_PI_2));
    let east = (0..21).map(|k| Pose2::new(2.0 + 0.25 * k as f32, 1.5, 0.0));
    let west = (1..21).map(|k| Pose2::new(7.0 - 0.25 * k as f32, 1.5, PI));
    let truth: Vec<Pose2> = south.chain(east).chain(west).collect();
    let drift = Pose2::new(0.25, -0.1, 0.04);
    let graph = truth
        .iter()
        .enumerate()
        .map(|(k, &t)| if k < RETURN { t } else { drift.compose(t) })
        .collect();
    let keyframes = truth
        .iter()
        .enumerate()
        .map(|(k, &t)| Keyframe::new(&scan(t, &walls), t, k / 5, 0.25 * k as f32, false))
        .collect();
    (keyframes, graph, truth)
}

/// The first keyframe of the way back.
const RETURN: usize = 35;

#[test]
fn a_path_retraced_the_other_way_closes_a_loop_with_the_true_relative_pose() {
    let (keyframes, graph, truth) = out_and_back();
    let mut closer = LoopCloser::<181>::new(LoopConfig::default());
    // Coming back past x = 3 m, facing the corner the old path turned at.
    let new = RETURN + 15;
    let candidates = closer.candidates(&keyframes[..=new], &graph, new);
    let old = *candidates
        .iter()
        .find(|&&j| j < RETURN)
        .expect("an outbound keyframe, facing the other way, is a candidate");
    let guess = graph[old].between(graph[new]);
    let edge = closer
        .verify(&keyframes, &graph, old, new, guess)
        .unwrap_or_else(|r| panic!("the revisit from {old} to {new} is refused: {r:?}"));
    let expected = truth[old].between(truth[new]);
    let (shift, turn) = edge.measurement.distance_to(expected);
    assert!(
        shift < 0.03 && turn < 0.01,
        "measured {:?}, true {expected:?} (graph guess {guess:?})",
        edge.measurement
    );
}

#[test]
fn the_candidate_alone_does_not_hold_what_the_revisit_sees() {
    // Why the old keyframes around the candidate are needed: with none, the candidate's own
    // 180° scan faces away from everything the new keyframe sees but the side walls.
    let (keyframes, graph, _) = out_and_back();
    let config = LoopConfig {
        reference_neighbours: 0,
        reference_neighbours_opposite: 0,
        ..LoopConfig::default()
    };
    let mut closer = LoopCloser::<181>::new(config);
    // The old keyframe at x = 3 m faced east; the new one there faces west.
    let (old, new) = (18, RETURN + 15);
    let guess = graph[old].between(graph[new]);
    assert!(closer.verify(&keyframes, &graph, old, new, guess).is_err());
}

#[test]
fn sparse_keyframes_may_verify_more_candidates_than_dense_ones() {
    // The loop search is budgeted per second of log: a keyframe that follows the previous one
    // after a long gap may verify a second candidate, one that follows it closely only one.
    let config = LoopConfig {
        max_candidates: 2,
        candidate_interval_s: 0.7,
        ..LoopConfig::default()
    };
    let closer = LoopCloser::<181>::new(config);
    let keyframe = |stamp_s: f64| Keyframe {
        stamp_s,
        beams: Vec::new(),
        tracking_pose: Pose2::IDENTITY,
        submap: 0,
        path_m: 0.0,
        predicted: false,
    };
    let keyframes: Vec<Keyframe> = [10.0, 10.35, 11.75, 40.0, 39.0]
        .into_iter()
        .map(keyframe)
        .collect();
    let budgets: Vec<usize> = (0..keyframes.len())
        .map(|k| closer.budget(&keyframes, k))
        .collect();
    // The first keyframe, a dense one, a sparse one, one after a stop (capped), and one whose
    // stamp went backwards (still one).
    assert_eq!(budgets, [1, 1, 2, 2, 1]);
    assert_eq!(
        closer.budget(&keyframes, 9),
        1,
        "a keyframe that does not exist"
    );
}

/// Final graph error of the step from keyframe 5 to 6 along y = 2.5 m in the room, heading east
/// from x = 4 m, when the tracker got that one step wrong by 8 cm sideways (and carried the
/// error on). Loop search is off, so only the back end's other edges can undo the step.
fn bad_step_error(skip_edge_span: usize) -> f32 {
    let walls = walls();
    let mut config = SlamConfig {
        skip_edge_span,
        ..SlamConfig::default()
    };
    config.loops.search_radius_m = 0.0;
    config.loops.drift_per_m = 0.0;
    let mut backend = Backend::<181>::new(config);
    let truth: Vec<Pose2> = (0..12)
        .map(|k| Pose2::new(4.0 + 0.25 * k as f32, 2.5, 0.0))
        .collect();
    for (k, &t) in truth.iter().enumerate() {
        let tracked = if k >= 6 {
            Pose2::new(t.x, t.y + 0.08, t.theta)
        } else {
            t
        };
        let mut keyframe = Keyframe::new(&scan(t, &walls), tracked, k / 5, 0.25 * k as f32, false);
        keyframe.stamp_s = 0.5 * k as f64;
        backend.add_keyframe(keyframe);
    }
    backend.finish();
    let graph = backend.poses();
    let step = graph[5].between(graph[6]);
    step.distance_to(truth[5].between(truth[6])).0
}

#[test]
fn a_keyframe_matched_against_the_one_two_before_it_undoes_a_bad_tracker_step() {
    let alone = bad_step_error(0);
    assert!(
        alone > 0.075,
        "the tracker's chain keeps its error ({alone} m)"
    );
    let with_skips = bad_step_error(2);
    assert!(
        with_skips < 0.05,
        "with direct matches two keyframes apart the step is {with_skips} m off (alone {alone} m)"
    );
}
