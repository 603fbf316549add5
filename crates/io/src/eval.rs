//! The relations metric (Kuemmerle et al. 2009; DESIGN.md §6).
//!
//! For each relation, the estimated motion d = inv(x_i) x_j is compared with the reference d*
//! through e = inv(d*) d. Relations whose timestamps are not both in the trajectory are counted,
//! never silently dropped; so are relations that touch a pose the trajectory marks lost
//! (predicted, not measured), which are not scored either.

use crate::relations::Relation;
use crate::trajectory::TrajectoryPoint;

/// Relation stamps carry as few as 5 decimals; scans are at least tens of ms apart.
pub const DEFAULT_TIME_TOLERANCE_S: f64 = 1e-3;

/// Relations spanning at most this long are "near" (what odometry is judged on); longer ones
/// are "far" (loop closures, where drift shows).
pub const NEAR_SPAN_S: f64 = 2.0;

/// Below this fraction of relations matched, a score describes a small, possibly unrepresentative
/// part of the run (often the wrong trajectory or a stamp offset), so it is reported with a warning.
pub const LOW_MATCH_RATIO: f64 = 0.5;

/// Why no score can be given: every mean would be over an empty set, and a mean error of 0.0 for
/// nothing would read as a perfect score.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    NoRelations,
    NoneMatched {
        relations: usize,
        on_lost: usize,
        tolerance_s: f64,
    },
}

impl std::fmt::Display for EvalError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EvalError::NoRelations => f.write_str("the relations file holds no relation: nothing to score"),
            EvalError::NoneMatched {
                relations,
                on_lost,
                tolerance_s,
            } => write!(
                f,
                "none of the {relations} relations has both timestamps at measured poses of the trajectory \
                 (within {tolerance_s} s; {on_lost} touch poses marked lost): is it the trajectory of the \
                 same log, and are its timestamps copied from the log?"
            ),
        }
    }
}

impl std::error::Error for EvalError {}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalSummary {
    pub relations: usize,
    pub matched: usize,
    /// `matched / relations`, in (0, 1].
    pub match_ratio: f64,
    /// Relations with both stamps in the trajectory but at least one on a pose marked lost.
    pub on_lost: usize,
    pub trans_mean_m: f64,
    pub trans_std_m: f64,
    pub trans2_mean_m2: f64,
    pub rot_mean_deg: f64,
    pub rot_std_deg: f64,
    pub rot2_mean_deg2: f64,
    pub near_matched: usize,
    pub near_trans_mean_m: f64,
    pub far_matched: usize,
    pub far_trans_mean_m: f64,
    /// Per matched relation: (index into the relations, translational error m, rotational error deg).
    pub errors: Vec<(usize, f64, f64)>,
}

/// Finds trajectory poses by timestamp within a tolerance, in a file that may be out of order.
struct StampIndex<'a> {
    sorted: Vec<(f64, usize)>,
    points: &'a [TrajectoryPoint],
    tolerance_s: f64,
}

impl<'a> StampIndex<'a> {
    fn new(points: &'a [TrajectoryPoint], tolerance_s: f64) -> Self {
        let mut sorted: Vec<(f64, usize)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (p.timestamp_s, i))
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        Self {
            sorted,
            points,
            tolerance_s,
        }
    }

    fn find(&self, t: f64) -> Option<&'a TrajectoryPoint> {
        let k = self.sorted.partition_point(|&(s, _)| s < t);
        [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter_map(|k| self.sorted.get(k))
            .map(|&(s, i)| ((s - t).abs(), i))
            .filter(|&(d, _)| d <= self.tolerance_s)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, i)| &self.points[i])
    }
}

/// Scores a trajectory; an error when not one relation could be scored.
pub fn evaluate(
    trajectory: &[TrajectoryPoint],
    relations: &[Relation],
    tolerance_s: f64,
) -> Result<EvalSummary, EvalError> {
    if relations.is_empty() {
        return Err(EvalError::NoRelations);
    }
    let index = StampIndex::new(trajectory, tolerance_s);
    let mut errors = Vec::new();
    let mut on_lost = 0;
    for (k, rel) in relations.iter().enumerate() {
        let (Some(a), Some(b)) = (index.find(rel.t1_s), index.find(rel.t2_s)) else {
            continue;
        };
        if a.lost || b.lost {
            on_lost += 1;
            continue;
        }
        let estimated = a.pose.between(b.pose);
        let e = rel.motion.inverse().compose(estimated);
        errors.push((k, e.x_m.hypot(e.y_m), e.theta_rad.abs().to_degrees()));
    }
    if errors.is_empty() {
        return Err(EvalError::NoneMatched {
            relations: relations.len(),
            on_lost,
            tolerance_s,
        });
    }
    let (trans_mean_m, trans_std_m, trans2_mean_m2) = moments(errors.iter().map(|e| e.1));
    let (rot_mean_deg, rot_std_deg, rot2_mean_deg2) = moments(errors.iter().map(|e| e.2));
    let is_near = |k: usize| (relations[k].t2_s - relations[k].t1_s).abs() <= NEAR_SPAN_S;
    let near = errors.iter().filter(|e| is_near(e.0)).map(|e| e.1);
    let far = errors.iter().filter(|e| !is_near(e.0)).map(|e| e.1);
    Ok(EvalSummary {
        relations: relations.len(),
        matched: errors.len(),
        match_ratio: errors.len() as f64 / relations.len() as f64,
        on_lost,
        trans_mean_m,
        trans_std_m,
        trans2_mean_m2,
        rot_mean_deg,
        rot_std_deg,
        rot2_mean_deg2,
        near_matched: near.clone().count(),
        near_trans_mean_m: moments(near).0,
        far_matched: far.clone().count(),
        far_trans_mean_m: moments(far).0,
        errors,
    })
}

/// Mean, population standard deviation and mean square; zeros for an empty set.
fn moments(values: impl Iterator<Item = f64> + Clone) -> (f64, f64, f64) {
    let n = values.clone().count();
    if n == 0 {
        return (0.0, 0.0, 0.0);
    }
    let mean = values.clone().sum::<f64>() / n as f64;
    let mean2 = values.clone().map(|v| v * v).sum::<f64>() / n as f64;
    let var = values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
    (mean, var.sqrt(), mean2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::carmen::OdomPose;

    fn point(t: f64, x: f64, y: f64, th: f64) -> TrajectoryPoint {
        TrajectoryPoint {
            timestamp_text: format!("{t}"),
            timestamp_s: t,
            pose: OdomPose::new(x, y, th),
            lost: false,
        }
    }

    #[test]
    fn a_perfect_trajectory_scores_zero_and_a_shifted_one_scores_the_shift() {
        let truth = [
            point(1.0, 0.0, 0.0, 0.0),
            point(2.0, 1.0, 0.0, 0.5),
            point(3.0, 1.5, 1.0, 1.5),
        ];
        let rel = |i: usize, j: usize| Relation {
            t1_s: truth[i].timestamp_s,
            t2_s: truth[j].timestamp_s + 4e-6,
            motion: truth[i].pose.between(truth[j].pose),
        };
        let rels = [rel(0, 1), rel(1, 2), rel(2, 0)];
        let s = evaluate(&truth, &rels, DEFAULT_TIME_TOLERANCE_S).unwrap();
        assert_eq!((s.relations, s.matched), (3, 3));
        assert!(s.trans_mean_m < 1e-9 && s.rot_mean_deg < 1e-9);

        // The last pose moved 0.3 m along its own x axis: every relation touching it is off by 0.3 m.
        let mut bent = truth.clone();
        bent[2].pose = truth[2].pose.compose(OdomPose::new(0.3, 0.0, 0.0));
        let s = evaluate(&bent, &rels[1..2], DEFAULT_TIME_TOLERANCE_S).unwrap();
        assert!((s.trans_mean_m - 0.3).abs() < 1e-9, "{}", s.trans_mean_m);
        assert!(s.rot_mean_deg < 1e-9);
    }

    #[test]
    fn unmatched_relations_are_counted_not_scored() {
        let traj = [point(1.0, 0.0, 0.0, 0.0), point(2.0, 1.0, 0.0, 0.0)];
        let rels = [
            Relation {
                t1_s: 1.0,
                t2_s: 2.0,
                motion: OdomPose::new(1.0, 0.0, 0.0),
            },
            Relation {
                t1_s: 1.0,
                t2_s: 2.5,
                motion: OdomPose::new(1.0, 0.0, 0.0),
            },
        ];
        let s = evaluate(&traj, &rels, DEFAULT_TIME_TOLERANCE_S).unwrap();
        assert_eq!((s.relations, s.matched), (2, 1));
        assert_eq!(s.match_ratio, 0.5);
    }

    #[test]
    fn out_of_order_stamps_are_found() {
        let traj = [
            point(3.0, 3.0, 0.0, 0.0),
            point(1.0, 1.0, 0.0, 0.0),
            point(2.0, 2.0, 0.0, 0.0),
        ];
        let rels = [Relation {
            t1_s: 1.0,
            t2_s: 3.0,
            motion: OdomPose::new(2.0, 0.0, 0.0),
        }];
        let s = evaluate(&traj, &rels, DEFAULT_TIME_TOLERANCE_S).unwrap();
        assert_eq!(s.matched, 1);
        assert!(s.trans_mean_m < 1e-12);
    }

    #[test]
    fn nothing_to_score_is_an_error_not_a_perfect_score() {
        let traj = [point(1.0, 0.0, 0.0, 0.0), point(2.0, 1.0, 0.0, 0.0)];
        assert_eq!(
            evaluate(&traj, &[], DEFAULT_TIME_TOLERANCE_S),
            Err(EvalError::NoRelations)
        );
        let elsewhere = [Relation {
            t1_s: 10.0,
            t2_s: 11.0,
            motion: OdomPose::new(1.0, 0.0, 0.0),
        }];
        assert!(matches!(
            evaluate(&traj, &elsewhere, DEFAULT_TIME_TOLERANCE_S),
            Err(EvalError::NoneMatched { relations: 1, .. })
        ));
        // One stamp in the trajectory is not enough: a relation needs both ends.
        let half = [Relation {
            t1_s: 1.0,
            t2_s: 11.0,
            motion: OdomPose::new(1.0, 0.0, 0.0),
        }];
        assert!(evaluate(&traj, &half, DEFAULT_TIME_TOLERANCE_S).is_err());
    }

    #[test]
    fn relations_touching_lost_poses_are_counted_not_scored() {
        let mut traj = [
            point(1.0, 0.0, 0.0, 0.0),
            point(2.0, 1.0, 0.0, 0.0),
            point(3.0, 9.0, 9.0, 3.0),
        ];
        traj[2].lost = true;
        let rel = |t1: f64, t2: f64| Relation {
            t1_s: t1,
            t2_s: t2,
            motion: OdomPose::new(t2 - t1, 0.0, 0.0),
        };
        let s = evaluate(
            &traj,
            &[rel(1.0, 2.0), rel(2.0, 3.0)],
            DEFAULT_TIME_TOLERANCE_S,
        )
        .unwrap();
        assert_eq!((s.matched, s.on_lost), (1, 1));
        assert!(s.trans_mean_m < 1e-12, "the lost pose is not scored");
        assert!(matches!(
            evaluate(&traj, &[rel(2.0, 3.0)], DEFAULT_TIME_TOLERANCE_S),
            Err(EvalError::NoneMatched { on_lost: 1, .. })
        ));
    }
}
