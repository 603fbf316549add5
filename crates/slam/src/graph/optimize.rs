//! Sparse Levenberg-Marquardt on the pose graph.
//!
//! Each iteration linearises every edge ([`super::residual`]), adds the weighted blocks into
//! the upper triangle of the sparse Hessian laid out by [`Pattern`], and solves the damped
//! normal equations with faer's sparse Cholesky, reusing the symbolic factorisation. Damping
//! follows Marquardt (the diagonal scaled by `1 + lambda`), so edges whose information differs
//! by many orders of magnitude are damped alike, and lambda is updated by Nielsen's gain-ratio
//! rule (Madsen, Nielsen and Tingleff, "Methods for non-linear least squares problems", 2004,
//! section 3.2). Loop edges are reweighted every iteration by the robust kernel.
//!
//! Warm start: the current poses are the initial guess, so after one more loop edge the solver
//! usually needs only a few iterations. A call on a graph that has not changed since its last
//! converged optimisation (same settings) returns at once.

use super::edge::{EdgeId, EdgeKind, NodeId};
use super::graduation::{edge_kernels, stage_kernels, worst_undecided_chi2};
use super::kernel::LoopKernel;
use super::pattern::{anchored_nodes, Pattern};
use super::pose::Pose2d;
use super::pose_graph::PoseGraph;
use super::residual::{chi2, linearize, mul, mul_vec, transpose_mul};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use std::time::{Duration, Instant};

/// Initial Marquardt damping: small, because a warm-started graph is near its optimum.
const INITIAL_LAMBDA: f64 = 1e-5;

/// Optimiser settings; the defaults suit graphs of keyframes a few decimetres apart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizeConfig {
    /// Upper bound on linearise-and-solve iterations (accepted steps).
    pub max_iterations: usize,
    /// Stop when a step lowers the cost by less than this fraction of it.
    pub relative_tolerance: f64,
    /// Kernel on loop edges; odometry edges are always plain least squares.
    pub loop_kernel: LoopKernel,
    /// A loop edge whose final weight is below this is reported as down-weighted (rejected).
    pub downweighted_below: f64,
    /// Graduated non-convexity: the kernel threshold starts above every loop's error and is
    /// divided by this factor each stage down to the kernel's own (see `super::graduation`).
    /// None runs the kernel as it is from the start.
    pub graduation_step: Option<f64>,
}

impl Default for OptimizeConfig {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            relative_tolerance: 1e-6,
            loop_kernel: LoopKernel::Dcs { phi: 5.0 },
            downweighted_below: 0.1,
            graduation_step: Some(2.0),
        }
    }
}

/// Why the optimiser stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The cost stopped falling (relative decrease below tolerance) or reached zero.
    Converged,
    /// Nothing to move: every node is fixed or anchored.
    NothingToOptimize,
    /// `max_iterations` accepted steps and still improving.
    MaxIterations,
    /// No damping found a step that lowers the cost (the poses are kept as they were).
    NoDescent,
    /// The solver could not allocate its workspace.
    OutOfMemory,
}

#[derive(Clone, Debug, PartialEq)]
pub struct OptimizeReport {
    /// Accepted steps.
    pub iterations: usize,
    /// Sum over edges of the kernel's cost of `e^T Omega e`, before and after.
    pub initial_chi2: f64,
    pub final_chi2: f64,
    pub elapsed: Duration,
    pub converged: bool,
    pub stop: StopReason,
    /// Final information scale of every edge, indexed by `EdgeId::index` (1 for odometry).
    pub edge_weights: Vec<f64>,
    /// Loop edges whose final weight is below `downweighted_below`: the ones the kernel rejected.
    pub downweighted_loops: Vec<EdgeId>,
    /// Nodes held still because nothing links their component to a fixed node.
    pub anchored: Vec<NodeId>,
}

impl PoseGraph {
    /// Moves the free nodes to minimise the (robust) squared error of all edges.
    pub fn optimize(&mut self, config: &OptimizeConfig) -> OptimizeReport {
        let start = Instant::now();
        let final_kernels = edge_kernels(self, config.loop_kernel, config.loop_kernel);
        let initial_chi2 = total_cost(self, self.nodes(), &final_kernels);
        let mut report = OptimizeReport {
            iterations: 0,
            initial_chi2,
            final_chi2: initial_chi2,
            elapsed: Duration::ZERO,
            converged: false,
            stop: StopReason::NothingToOptimize,
            edge_weights: Vec::new(),
            downweighted_loops: Vec::new(),
            anchored: Vec::new(),
        };
        let unchanged = self.settled == Some(*config);
        if self.pattern.is_none() && !unchanged {
            match Pattern::build(self.fixed_flags(), self.edges()) {
                Ok(p) => self.pattern = p,
                Err(_) => report.stop = StopReason::OutOfMemory,
            }
        }
        report.anchored = match &self.pattern {
            Some(pattern) => pattern.anchored.clone(),
            None => anchored_nodes(self.fixed_flags(), self.edges()),
        };
        if unchanged {
            report.stop = StopReason::Converged;
        } else if let Some(mut pattern) = self.pattern.take() {
            let stages = stage_kernels(self, config);
            for (k, &stage) in stages.iter().enumerate() {
                let last = k + 1 == stages.len();
                if let (false, false, LoopKernel::Dcs { phi }) = (k == 0, last, stage) {
                    if worst_undecided_chi2(self) <= phi {
                        continue;
                    }
                }
                let kernels = edge_kernels(self, stage, config.loop_kernel);
                // Intermediate stages only need to move the poses towards the next stage's
                // basin, not to converge: a loose tolerance and a few steps suffice.
                let (tolerance, budget) = if last {
                    (config.relative_tolerance, config.max_iterations)
                } else {
                    (1e-3, 5)
                };
                let lm = self.levenberg_marquardt(&mut pattern, &kernels, tolerance, budget);
                report.iterations += lm.1;
                report.stop = lm.0;
            }
            self.pattern = Some(pattern);
        }
        report.converged = matches!(
            report.stop,
            StopReason::Converged | StopReason::NothingToOptimize
        );
        report.final_chi2 = total_cost(self, self.nodes(), &final_kernels);
        report.edge_weights = self.edge_weights(&final_kernels);
        report.downweighted_loops = (self.edges().iter().zip(&report.edge_weights))
            .enumerate()
            .filter(|(_, (e, &w))| e.kind == EdgeKind::Loop && w < config.downweighted_below)
            .map(|(i, _)| EdgeId(i as u32))
            .collect();
        self.remember_rejected(&report.downweighted_loops);
        self.settled = report.converged.then_some(*config);
        report.elapsed = start.elapsed();
        report
    }

    fn levenberg_marquardt(
        &mut self,
        pattern: &mut Pattern,
        kernels: &[LoopKernel],
        tolerance: f64,
        max_iterations: usize,
    ) -> (StopReason, usize) {
        let mut iterations = 0;
        let n = 3 * pattern.vars;
        let mut hessian = vec![0.0; pattern.row_idx.len()];
        let mut damped = vec![0.0; hessian.len()];
        let mut gradient = vec![0.0; n];
        let mut step = vec![0.0; n];
        let mut trial: Vec<Pose2d> = self.nodes().to_vec();
        let mut cost = total_cost(self, self.nodes(), kernels);
        let (mut lambda, mut nu) = (INITIAL_LAMBDA, 2.0);
        let symbolic =
            SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
        for _ in 0..max_iterations {
            if cost <= f64::MIN_POSITIVE {
                return (StopReason::Converged, iterations);
            }
            self.assemble(pattern, kernels, &mut hessian, &mut gradient);
            loop {
                if lambda > 1e16 {
                    return (StopReason::NoDescent, iterations);
                }
                damped.copy_from_slice(&hessian);
                for diag in &pattern.diagonal {
                    for (k, &col) in diag.iter().enumerate() {
                        let d = &mut damped[col + k];
                        *d += lambda * d.abs().max(1e-12);
                    }
                }
                for (s, g) in step.iter_mut().zip(&gradient) {
                    *s = -g;
                }
                let matrix = SparseColMatRef::new(symbolic, &damped);
                if !pattern.solver.solve(matrix, &mut step) {
                    (lambda, nu) = (lambda * nu, nu * 2.0);
                    continue;
                }
                // Decrease the damped linear model promises: -h.g + lambda h^T D h.
                let mut predicted = 0.0;
                for (k, (s, g)) in step.iter().zip(&gradient).enumerate() {
                    let diag = &pattern.diagonal[k / 3];
                    let d = hessian[diag[k % 3] + k % 3].abs().max(1e-12);
                    predicted += -s * g + lambda * d * s * s;
                }
                if !predicted.is_finite() {
                    (lambda, nu) = (lambda * nu, nu * 2.0);
                    continue;
                }
                // A step promising (almost) nothing means the gradient is (almost) zero.
                if predicted <= 1e-3 * tolerance * cost {
                    return (StopReason::Converged, iterations);
                }
                trial.copy_from_slice(self.nodes());
                for (v, &node) in pattern.node_of_var.iter().enumerate() {
                    let p = trial[node];
                    let h = &step[3 * v..3 * v + 3];
                    trial[node] = Pose2d::new(p.x + h[0], p.y + h[1], p.theta + h[2]);
                }
                let new_cost = total_cost(self, &trial, kernels);
                let gain = (cost - new_cost) / predicted;
                if gain > 0.0 && new_cost.is_finite() {
                    self.poses_mut().copy_from_slice(&trial);
                    iterations += 1;
                    lambda *= (1.0 - (2.0 * gain - 1.0).powi(3)).max(1.0 / 3.0);
                    nu = 2.0;
                    let decrease = cost - new_cost;
                    cost = new_cost;
                    if decrease <= tolerance * (cost + decrease) {
                        return (StopReason::Converged, iterations);
                    }
                    break;
                }
                (lambda, nu) = (lambda * nu, nu * 2.0);
            }
        }
        (StopReason::MaxIterations, iterations)
    }

    /// Writes `H = sum J^T W J` (upper triangle) and `g = sum J^T W e` at the current poses.
    fn assemble(
        &self,
        pattern: &Pattern,
        kernels: &[LoopKernel],
        hessian: &mut [f64],
        gradient: &mut [f64],
    ) {
        hessian.fill(0.0);
        gradient.fill(0.0);
        let poses = self.nodes();
        for ((edge, slots), kernel) in self.edges().iter().zip(&pattern.edges).zip(kernels) {
            let lin = linearize(
                poses[edge.from.index()],
                poses[edge.to.index()],
                edge.measurement,
            );
            let w = kernel.weight(chi2(&lin.error, &edge.information));
            let omega = edge.information.map(|row| row.map(|v| v * w));
            let a_omega = transpose_mul(&lin.d_from, &omega);
            let b_omega = transpose_mul(&lin.d_to, &omega);
            for (var, j, j_omega) in [
                (slots.from_var, &lin.d_from, &a_omega),
                (slots.to_var, &lin.d_to, &b_omega),
            ] {
                let Some(v) = var else { continue };
                let block = mul(j_omega, j);
                for (c, &col) in pattern.diagonal[v].iter().enumerate() {
                    for (r, row) in block.iter().enumerate().take(c + 1) {
                        hessian[col + r] += row[c];
                    }
                }
                for (g, e) in gradient[3 * v..3 * v + 3]
                    .iter_mut()
                    .zip(mul_vec(j_omega, &lin.error))
                {
                    *g += e;
                }
            }
            if let (Some(cols), Some(f), Some(t)) =
                (slots.off_diagonal, slots.from_var, slots.to_var)
            {
                // Rows belong to the lower-numbered unknown: A^T W B if that is `from`, else its transpose.
                let block = mul(&a_omega, &lin.d_to);
                for (c, &col) in cols.iter().enumerate() {
                    for r in 0..3 {
                        hessian[col + r] += if f < t { block[r][c] } else { block[c][r] };
                    }
                }
            }
        }
    }

    /// Every edge's kernel weight at the current poses.
    fn edge_weights(&self, kernels: &[LoopKernel]) -> Vec<f64> {
        let poses = self.nodes();
        (self.edges().iter().zip(kernels))
            .map(|(e, kernel)| {
                let lin = linearize(poses[e.from.index()], poses[e.to.index()], e.measurement);
                kernel.weight(chi2(&lin.error, &e.information))
            })
            .collect()
    }
}

/// The objective: each edge's kernel cost of `e^T Omega e` (plain for odometry), summed.
pub(super) fn total_cost(graph: &PoseGraph, poses: &[Pose2d], kernels: &[LoopKernel]) -> f64 {
    (graph.edges().iter().zip(kernels))
        .map(|(e, kernel)| {
            let lin = linearize(poses[e.from.index()], poses[e.to.index()], e.measurement);
            kernel.cost(chi2(&lin.error, &e.information))
        })
        .sum()
}
