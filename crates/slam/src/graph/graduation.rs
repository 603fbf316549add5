//! Graduated non-convexity for the loop kernel (Yang, Antonante, Tzoumas and Carlone,
//! "Graduated non-convexity for robust spatial perception", RA-L 2020).
//!
//! DCS judges a loop by its error at the current poses. After a long stretch of drift a
//! correct loop can be off by many of its own sigmas, and DCS alone switches it off before the
//! odometry chain has had a chance to bend towards it: a local minimum the synthetic tests hit
//! on a third of their loops. So the optimiser first uses a threshold `mu * phi` large enough
//! to accept every undecided loop (plain least squares for them, which has no such minima),
//! then divides `mu` by `graduation_step` stage by stage down to 1: loops the rest of the graph
//! agrees with settle to small errors on the way, and only those it disagrees with lose their
//! weight. A stage whose threshold is above every undecided loop's current error would solve
//! the same problem as the stage before, so it is skipped: once the loops agree, the rest of
//! the graduation costs nothing.
//!
//! Loops the previous optimisation rejected keep the final kernel throughout, so a false loop
//! found once does not bend the map again at every later call (and does not make every call
//! start from least squares); it is still re-weighted each iteration and comes back if the
//! graph comes to agree with it. When every other loop already agrees (the usual warm-started
//! call) there is a single stage.

use super::edge::EdgeKind;
use super::kernel::LoopKernel;
use super::optimize::OptimizeConfig;
use super::pose_graph::PoseGraph;
use super::residual::{chi2, linearize};

/// At most this many stages: with a factor of 2 that covers chi2 ratios of 2^24.
const MAX_STAGES: usize = 24;

/// The loop kernels of each stage, loosest first, ending with the configured one.
pub(super) fn stage_kernels(graph: &PoseGraph, config: &OptimizeConfig) -> Vec<LoopKernel> {
    let (LoopKernel::Dcs { phi }, Some(step)) = (config.loop_kernel, config.graduation_step) else {
        return vec![config.loop_kernel];
    };
    let worst = worst_undecided_chi2(graph);
    let mut stages = vec![config.loop_kernel];
    let mut mu = 1.0;
    while phi * mu < worst && stages.len() < MAX_STAGES && step > 1.0 {
        mu *= step;
        stages.push(LoopKernel::Dcs { phi: phi * mu });
    }
    stages.reverse();
    stages
}

/// The largest error among loops the last optimisation did not reject: a stage whose
/// threshold is above it weights every such loop fully, like the stage before it.
pub(super) fn worst_undecided_chi2(graph: &PoseGraph) -> f64 {
    let poses = graph.nodes();
    (graph.edges().iter().enumerate())
        .filter(|(k, e)| e.kind == EdgeKind::Loop && !graph.was_rejected(*k))
        .map(|(_, e)| {
            let lin = linearize(poses[e.from.index()], poses[e.to.index()], e.measurement);
            chi2(&lin.error, &e.information)
        })
        .fold(0.0, f64::max)
}

/// Each edge's kernel in one stage: none for odometry, `base` for loops rejected last time,
/// `stage` for the others.
pub(super) fn edge_kernels(
    graph: &PoseGraph,
    stage: LoopKernel,
    base: LoopKernel,
) -> Vec<LoopKernel> {
    (graph.edges().iter().enumerate())
        .map(|(k, e)| match e.kind {
            EdgeKind::Odometry => LoopKernel::None,
            EdgeKind::Loop if graph.was_rejected(k) => base,
            EdgeKind::Loop => stage,
        })
        .collect()
}
