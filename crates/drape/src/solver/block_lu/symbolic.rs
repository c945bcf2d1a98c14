//! The symbolic analysis of the block LU, made once per pattern: the
//! ordering (approximate minimum degree, then a cut of the node graph in
//! two halves and a separator by a level set), where the blocks of `A`
//! lie in the scalar values, and the pattern of `L` by the elimination
//! tree.

use super::{BlockLuError, NONE, Source, Symbolic};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::{FaerError, SymbolicSparseColMatRef};
use std::ops::Range;

/// Below this many nodes the ordering is not split in two.
const SPLIT_MIN_NODES: usize = 100;

/// Level sets tried as separators (the best balanced ones).
const CUT_CANDIDATES: usize = 5;

impl Symbolic {
    /// The analysis of the node graph for the ordering `perm`
    /// (`perm_inv` its inverse) split as `split`.
    pub(super) fn new(
        node_ptr: &[usize],
        node_rows: &[usize],
        perm: Vec<usize>,
        perm_inv: &[usize],
        split: (usize, usize),
    ) -> Result<Self, BlockLuError> {
        let n = perm.len();
        // Permuted columns: the rows of each, and the value sources.
        let mut col_src_ptr = vec![0; n + 1];
        let mut row_src_ptr = vec![0; n + 1];
        let mut col_src = Vec::with_capacity(node_rows.len() / 2 + n);
        let mut row_src = Vec::with_capacity(node_rows.len() / 2);
        let mut lower: Vec<(u32, Source)> = Vec::new();
        let mut upper: Vec<(u32, Source)> = Vec::new();
        for jn in 0..n {
            let b = perm[jn];
            let deg = node_ptr[b + 1] - node_ptr[b];
            lower.clear();
            upper.clear();
            for p in node_ptr[b]..node_ptr[b + 1] {
                let a = node_rows[p];
                let i_new = perm_inv[a] as u32;
                // Block (a, b) of A is block (I, J) of P A P^T.
                let src = Source {
                    row: i_new,
                    base: 9 * node_ptr[b] + 3 * (p - node_ptr[b]),
                    stride: 3 * deg,
                };
                if i_new as usize >= jn {
                    lower.push((i_new, src));
                }
                if (i_new as usize) > jn {
                    // Block (J, I) = (b, a) of A: position of b in column a.
                    let q = node_rows[node_ptr[a]..node_ptr[a + 1]]
                        .binary_search(&b)
                        .map_err(|_| BlockLuError::NotSymmetric { row: a, column: b })?;
                    let deg_a = node_ptr[a + 1] - node_ptr[a];
                    upper.push((
                        i_new,
                        Source {
                            row: i_new,
                            base: 9 * node_ptr[a] + 3 * q,
                            stride: 3 * deg_a,
                        },
                    ));
                }
            }
            lower.sort_unstable_by_key(|e| e.0);
            upper.sort_unstable_by_key(|e| e.0);
            col_src.extend(lower.iter().map(|e| e.1));
            row_src.extend(upper.iter().map(|e| e.1));
            col_src_ptr[jn + 1] = col_src.len();
            row_src_ptr[jn + 1] = row_src.len();
        }
        let (l_ptr, l_rows) = l_pattern(n, |j, rows| {
            rows.extend(
                col_src[col_src_ptr[j]..col_src_ptr[j + 1]]
                    .iter()
                    .map(|s| s.row)
                    .filter(|&i| i as usize != j),
            )
        });
        Ok(Self {
            perm,
            l_ptr,
            l_rows,
            col_src_ptr,
            col_src,
            row_src_ptr,
            row_src,
            split,
        })
    }

    pub(super) fn nodes(&self) -> usize {
        self.perm.len()
    }

    /// Multiply–adds of the columns `range` (symmetric, non-symmetric):
    /// column `k` updates `sum_{m=1..c} m` blocks of `x_col` and as many
    /// minus one of `x_row`, 27 multiply–adds each.
    pub(super) fn flops(&self, range: Range<usize>) -> (f64, f64) {
        range.fold((0.0, 0.0), |(s, g), k| {
            let c = (self.l_ptr[k + 1] - self.l_ptr[k]) as f64;
            (s + 27.0 * c * (c + 1.0) / 2.0, g + 27.0 * c * c)
        })
    }
}

/// AMD on the node graph: `(perm, perm_inv)`.
pub(super) fn amd_order(
    node_ptr: &[usize],
    node_rows: &[usize],
) -> Result<(Vec<usize>, Vec<usize>), BlockLuError> {
    let n = node_ptr.len() - 1;
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    if n == 0 {
        return Ok((perm, perm_inv));
    }
    let graph = SymbolicSparseColMatRef::new_checked(n, n, node_ptr, None, node_rows);
    let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, node_rows.len()))
        .map_err(|e| BlockLuError::Ordering(FaerError::from(e).into()))?;
    amd::order(
        &mut perm,
        &mut perm_inv,
        graph,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| BlockLuError::Ordering(e.into()))?;
    Ok((perm, perm_inv))
}

/// The strictly lower pattern of the Cholesky factor of a matrix with a
/// symmetric pattern, by the elimination tree: column `j` gathers the rows
/// `rows_of(j, ..)` pushes (its own entries below the diagonal) and those
/// of its children. Returns `(l_ptr, l_rows)`.
fn l_pattern(n: usize, mut rows_of: impl FnMut(usize, &mut Vec<u32>)) -> (Vec<usize>, Vec<u32>) {
    let mut l_ptr = vec![0usize; n + 1];
    let mut l_rows: Vec<u32> = Vec::new();
    let mut mark = vec![NONE; n];
    let mut child_head = vec![NONE; n];
    let mut child_next = vec![NONE; n];
    let mut own: Vec<u32> = Vec::new();
    let mut list: Vec<u32> = Vec::new();
    for j in 0..n {
        list.clear();
        own.clear();
        rows_of(j, &mut own);
        mark[j] = j as u32;
        for &i in &own {
            if mark[i as usize] != j as u32 {
                mark[i as usize] = j as u32;
                list.push(i);
            }
        }
        let mut c = child_head[j];
        while c != NONE {
            for &i in &l_rows[l_ptr[c as usize]..l_ptr[c as usize + 1]] {
                if mark[i as usize] != j as u32 {
                    mark[i as usize] = j as u32;
                    list.push(i);
                }
            }
            c = child_next[c as usize];
        }
        list.sort_unstable();
        l_rows.extend_from_slice(&list);
        l_ptr[j + 1] = l_rows.len();
        if let Some(&parent) = list.first() {
            child_next[j] = child_head[parent as usize];
            child_head[parent as usize] = j as u32;
        }
    }
    (l_ptr, l_rows)
}

/// Cuts a connected node graph in two by a level set of a breadth-first
/// search from a peripheral node (found as in George & Liu 1979: restart
/// from a node of least degree in the last level while the number of
/// levels grows). Candidates are the [`CUT_CANDIDATES`] best-balanced
/// levels that leave at least a quarter of the nodes on each side (the
/// two sides then share no edge); for each, the ordering — `order`'s
/// nodes of the first side, those of the second, those of the level, each
/// in `order`'s sequence — and the split `(a, b)`. None for small or
/// disconnected graphs.
pub(super) fn bisect(
    node_ptr: &[usize],
    node_rows: &[usize],
    order: &[usize],
) -> Vec<(Vec<usize>, (usize, usize))> {
    let n = node_ptr.len() - 1;
    if n < SPLIT_MIN_NODES {
        return Vec::new();
    }
    let degree = |v: usize| node_ptr[v + 1] - node_ptr[v];
    let mut level = vec![usize::MAX; n];
    let mut queue = Vec::with_capacity(n);
    let mut bfs = |root: usize, level: &mut Vec<usize>| -> usize {
        level.fill(usize::MAX);
        queue.clear();
        queue.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for &w in &node_rows[node_ptr[v]..node_ptr[v + 1]] {
                if level[w] == usize::MAX {
                    level[w] = level[v] + 1;
                    queue.push(w);
                }
            }
        }
        queue.len()
    };
    let Some(mut root) = (0..n).min_by_key(|&v| degree(v)) else {
        return Vec::new();
    };
    let mut depth = 0;
    // Whether `level` holds the levels from `root`.
    let mut current = false;
    for _ in 0..8 {
        if bfs(root, &mut level) < n {
            return Vec::new();
        }
        current = true;
        let last = level.iter().copied().max().unwrap_or(0);
        if last <= depth {
            break;
        }
        depth = last;
        let next = (0..n)
            .filter(|&v| level[v] == last)
            .min_by_key(|&v| degree(v))
            .unwrap_or(root);
        current = next == root;
        root = next;
    }
    if !current {
        bfs(root, &mut level);
    }
    let depth = level.iter().copied().max().unwrap_or(0);
    let mut sizes = vec![0usize; depth + 1];
    for &l in &level {
        sizes[l] += 1;
    }
    // The levels that leave at least a quarter of the nodes on each side,
    // best balanced first.
    let mut below = 0;
    let mut cuts = Vec::new();
    for (l, &size) in sizes.iter().enumerate() {
        let above = n - below - size;
        if l > 0 && l < depth && below.min(above) >= n / 4 {
            cuts.push((below.abs_diff(above), l));
        }
        below += size;
    }
    cuts.sort_unstable();
    cuts.truncate(CUT_CANDIDATES);
    cuts.into_iter()
        .map(|(_, cut)| {
            let side = |v: usize| (level[v] > cut) as usize + 2 * (level[v] == cut) as usize;
            let mut perm = Vec::with_capacity(n);
            for s in 0..3 {
                perm.extend(order.iter().copied().filter(|&v| side(v) == s));
            }
            let a = order.iter().filter(|&&v| side(v) == 0).count();
            let b = a + order.iter().filter(|&&v| side(v) == 1).count();
            (perm, (a, b))
        })
        .collect()
}
