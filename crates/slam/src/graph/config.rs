//! The optimiser's settings, apart from the optimiser: the graph remembers the settings it
//! last converged under, and the graduation schedule reads them, without either depending on
//! the solver.

use super::kernel::LoopKernel;

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
