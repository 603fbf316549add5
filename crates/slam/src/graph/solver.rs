//! The sparse Cholesky solve of the normal equations, on faer.
//!
//! faer's default symbolic analysis runs approximate minimum degree (AMD) on the scalar
//! matrix, nine entries per pose pair; on a 2,000-pose graph that analysis cost more than ten
//! numeric factorisations, and it is redone whenever an edge is added. Every pose is a 3x3
//! block, so the fill-reducing order is computed on the block graph (one entry per pose pair,
//! the structure the pose graph really has) and expanded to the three unknowns of each pose.
//! The numeric factor and the workspace are reused across iterations.
//!
//! The factorisation is always supernodal. faer picks the simplicial one for a pose graph's
//! few flops per factor entry, but that one works entry by entry, while every pose's three
//! unknowns share their column pattern and make a supernode of at least three columns that
//! the supernodal one factors as dense blocks: on an exploration flight of Intel whose graph
//! grew to 900 poses, a solve took about half the time.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Arc;

#[derive(Clone, Debug)]
pub(super) struct Solver {
    /// Shared, because it is not `Clone` and only the numeric factor differs between clones.
    symbolic: Arc<SymbolicCholesky<usize>>,
    factor: Vec<f64>,
    /// Workspace bytes for one factorisation and one solve; allocated per call to keep the
    /// type `Clone` (a pose graph is cloned by its users), which costs microseconds.
    scratch: StackReq,
}

impl Solver {
    /// Symbolic analysis of the upper-triangular pattern (`col_ptr`, `row_idx`) whose unknowns
    /// come in blocks of three; `block_col_ptr` and `block_row_idx` are the same pattern with
    /// one entry per block.
    pub fn new(
        col_ptr: &[usize],
        row_idx: &[usize],
        block_col_ptr: &[usize],
        block_row_idx: &[usize],
    ) -> Result<Self, FaerError> {
        let blocks = block_col_ptr.len() - 1;
        let (mut block_perm, mut block_inv) = (vec![0usize; blocks], vec![0usize; blocks]);
        let block_matrix = SymbolicSparseColMatRef::new_checked(
            blocks,
            blocks,
            block_col_ptr,
            None,
            block_row_idx,
        );
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(blocks, block_row_idx.len()))?;
        amd::order(
            &mut block_perm,
            &mut block_inv,
            block_matrix,
            amd::Control::default(),
            MemStack::new(&mut mem),
        )?;
        let perm: Vec<usize> = (block_perm.iter())
            .flat_map(|&b| 3 * b..3 * b + 3)
            .collect();
        let inv: Vec<usize> = (block_inv.iter()).flat_map(|&b| 3 * b..3 * b + 3).collect();
        let n = 3 * blocks;
        let matrix = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            matrix,
            Side::Upper,
            SymmetricOrdering::Custom(PermRef::new_checked(&perm, &inv, n)),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )?;
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        Ok(Self {
            factor: vec![0.0; symbolic.len_val()],
            symbolic: Arc::new(symbolic),
            scratch,
        })
    }

    /// Factors `matrix` (upper triangle, the analysed pattern) and overwrites `rhs` with the
    /// solution; false when the matrix is not positive definite (more damping needed) or the
    /// workspace cannot be allocated.
    pub fn solve(&mut self, matrix: SparseColMatRef<'_, usize, f64>, rhs: &mut [f64]) -> bool {
        let Ok(mut mem) = MemBuffer::try_new(self.scratch) else {
            return false;
        };
        let stack = MemStack::new(&mut mem);
        let Ok(llt) = self.symbolic.factorize_numeric_llt(
            &mut self.factor,
            matrix,
            Side::Upper,
            LltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        ) else {
            return false;
        };
        let n = rhs.len();
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
        true
    }
}
