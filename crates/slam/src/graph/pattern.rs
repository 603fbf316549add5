//! The shape of the normal equations: which nodes are unknowns, where each edge's 3x3 blocks
//! land in the sparse Hessian, and the Hessian's symbolic Cholesky factorisation.
//!
//! Everything here depends only on which nodes are joined by edges, not on the poses, so it is
//! computed once and reused by every iteration and every later call until the graph gains a
//! node, an edge or a fixed flag. The Hessian is stored as the upper triangle in compressed
//! columns; each unknown node owns three consecutive columns, and within a column the rows
//! are the node's lower-numbered neighbours (3 rows each, ascending) and then its own
//! diagonal block. Knowing those offsets up front lets assembly write straight into the value
//! array instead of sorting triplets every iteration.

use super::edge::{Edge, NodeId};
use super::solver::Solver;

/// Where one edge adds into the Hessian's value array.
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeSlots {
    /// Unknown index of each end (None for a fixed or anchored node).
    pub from_var: Option<usize>,
    pub to_var: Option<usize>,
    /// Positions of row 0 of the off-diagonal block in each of its three columns; the block
    /// sits in the columns of the higher-numbered unknown.
    pub off_diagonal: Option<[usize; 3]>,
}

#[derive(Clone, Debug)]
pub(super) struct Pattern {
    /// Number of unknown nodes (the system has three times as many rows).
    pub vars: usize,
    /// The node each unknown belongs to.
    pub node_of_var: Vec<usize>,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    /// Positions of row 0 of each unknown's diagonal block in its three columns.
    pub diagonal: Vec<[usize; 3]>,
    pub edges: Vec<EdgeSlots>,
    /// Nodes held still only because nothing joins their component to a fixed node.
    pub anchored: Vec<NodeId>,
    pub solver: Solver,
}

impl Pattern {
    /// Builds the pattern, or None when no node is free to move.
    pub fn build(
        fixed: &[bool],
        edges: &[Edge],
    ) -> Result<Option<Pattern>, faer::sparse::FaerError> {
        let n = fixed.len();
        let held = held_nodes(fixed, edges);
        let mut var_of_node = vec![None; n];
        let mut node_of_var = Vec::new();
        for (node, var) in var_of_node.iter_mut().enumerate() {
            if !held.held[node] {
                *var = Some(node_of_var.len());
                node_of_var.push(node);
            }
        }
        let vars = node_of_var.len();
        if vars == 0 {
            return Ok(None);
        }
        // Lower-numbered neighbours of each unknown, sorted and without repeats.
        let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); vars];
        for e in edges {
            if let (Some(a), Some(b)) = (var_of_node[e.from.index()], var_of_node[e.to.index()]) {
                neighbours[a.max(b)].push(a.min(b));
            }
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        let mut col_ptr = Vec::with_capacity(3 * vars + 1);
        let mut row_idx = Vec::new();
        let mut diagonal = Vec::with_capacity(vars);
        col_ptr.push(0);
        for (v, list) in neighbours.iter().enumerate() {
            let mut starts = [0; 3];
            for (b, start) in starts.iter_mut().enumerate() {
                for &r in list {
                    row_idx.extend(3 * r..3 * r + 3);
                }
                *start = row_idx.len();
                row_idx.extend(3 * v..=3 * v + b);
                col_ptr.push(row_idx.len());
            }
            diagonal.push(starts);
        }
        let slots = edges
            .iter()
            .map(|e| {
                let from_var = var_of_node[e.from.index()];
                let to_var = var_of_node[e.to.index()];
                let off_diagonal = from_var.zip(to_var).map(|(a, b)| {
                    let (lo, hi) = (a.min(b), a.max(b));
                    let k = neighbours[hi].binary_search(&lo).unwrap_or_default();
                    core::array::from_fn(|c| col_ptr[3 * hi + c] + 3 * k)
                });
                EdgeSlots {
                    from_var,
                    to_var,
                    off_diagonal,
                }
            })
            .collect();
        let mut block_col_ptr = vec![0];
        let mut block_row_idx = Vec::new();
        for (v, list) in neighbours.iter().enumerate() {
            block_row_idx.extend(list.iter().copied().chain([v]));
            block_col_ptr.push(block_row_idx.len());
        }
        let solver = Solver::new(&col_ptr, &row_idx, &block_col_ptr, &block_row_idx)?;
        Ok(Some(Pattern {
            vars,
            node_of_var,
            col_ptr,
            row_idx,
            diagonal,
            edges: slots,
            anchored: held.anchored,
            solver,
        }))
    }
}

/// Nodes held only for the gauge (see [`held_nodes`]).
pub(super) fn anchored_nodes(fixed: &[bool], edges: &[Edge]) -> Vec<NodeId> {
    held_nodes(fixed, edges).anchored
}

struct Held {
    held: Vec<bool>,
    anchored: Vec<NodeId>,
}

/// Fixed nodes, plus the lowest node of every connected component that has no fixed node
/// (without it that component could slide and turn freely and its Hessian would be singular).
fn held_nodes(fixed: &[bool], edges: &[Edge]) -> Held {
    let mut parent: Vec<usize> = (0..fixed.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for e in edges {
        let (a, b) = (
            root(&mut parent, e.from.index()),
            root(&mut parent, e.to.index()),
        );
        // The lower root wins, so each component's root is its lowest node.
        parent[a.max(b)] = a.min(b);
    }
    let mut has_fixed = vec![false; fixed.len()];
    for (node, &f) in fixed.iter().enumerate() {
        if f {
            let r = root(&mut parent, node);
            has_fixed[r] = true;
        }
    }
    let mut held = fixed.to_vec();
    let mut anchored = Vec::new();
    for node in 0..fixed.len() {
        if root(&mut parent, node) == node && !has_fixed[node] {
            held[node] = true;
            anchored.push(NodeId(node as u32));
        }
    }
    Held { held, anchored }
}

#[cfg(test)]
mod tests {
    use super::super::edge::test_edge;
    use super::super::pose::Pose2d;
    use super::*;

    fn edge(from: u32, to: u32) -> Edge {
        test_edge(from, to, Pose2d::IDENTITY)
    }

    #[test]
    fn each_floating_component_is_anchored_at_its_lowest_node() {
        // 0-1-2 holds the fixed node 0; 3-4 and 5 float; 6-7 joined through a later edge.
        let fixed = [true, false, false, false, false, false, false, false];
        let edges = [edge(0, 1), edge(2, 1), edge(4, 3), edge(7, 6)];
        let held = held_nodes(&fixed, &edges);
        assert_eq!(held.anchored, vec![NodeId(3), NodeId(5), NodeId(6)]);
        let p = Pattern::build(&fixed, &edges).unwrap().unwrap();
        assert_eq!(p.node_of_var, vec![1, 2, 4, 7]);
        // Unknowns 0 (node 1) and 1 (node 2) share a block: column 3 starts with rows 0..3.
        assert_eq!(&p.row_idx[p.col_ptr[3]..p.col_ptr[4]], &[0, 1, 2, 3]);
        assert_eq!(
            p.edges[1].off_diagonal,
            Some([p.col_ptr[3], p.col_ptr[4], p.col_ptr[5]])
        );
        assert!(p.edges[0].from_var.is_none() && p.edges[0].off_diagonal.is_none());
    }

    #[test]
    fn a_graph_with_nothing_free_has_no_pattern() {
        assert!(Pattern::build(&[true], &[]).unwrap().is_none());
        assert!(Pattern::build(&[], &[]).unwrap().is_none());
    }
}
