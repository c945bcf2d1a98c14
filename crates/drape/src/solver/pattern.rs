//! The sparsity pattern of the Hessian, computed once per mesh, and the
//! element colouring used for parallel assembly.
//!
//! The pattern is the node graph (nodes sharing an element), expanded to
//! 3x3 blocks, stored in compressed sparse columns (CSC) with sorted rows.
//! Column `3b + j` holds, for each neighbour `a` of node `b` in increasing
//! order, the rows `3a, 3a + 1, 3a + 2`; so the value index of entry `(3a +
//! i, 3b + j)` follows from the node-graph position `p` of `a` in column `b`
//! without a search:
//!
//! ```text
//! index = 9 ptr[b] + 3 j deg(b) + 3 (p - ptr[b]) + i
//! ```
//!
//! Element blocks `(a, b)` store `p` once ([`SparsePattern::element_blocks`]),
//! so assembly scatters straight into the CSC values ("scatter map").

use crate::block3::Block;

/// [`SparsePattern::block_layout`] for a node graph's pointers `ptr`
/// alone (the layout of the module docs).
#[inline]
pub(crate) fn block_layout(ptr: &[usize], p: usize, b: usize) -> (usize, usize) {
    let start = ptr[b];
    (9 * start + 3 * (p - start), 3 * (ptr[b + 1] - start))
}

/// CSC pattern of the DOF-level Hessian plus the node graph behind it.
#[derive(Debug, Clone)]
pub struct SparsePattern {
    /// Node graph: column `b` lists rows `node_rows[node_ptr[b]..node_ptr[b + 1]]`.
    node_ptr: Vec<usize>,
    node_rows: Vec<usize>,
    /// DOF-level CSC column pointers (length `3 nodes + 1`).
    pub col_ptr: Vec<usize>,
    /// DOF-level CSC row indices, sorted within each column.
    pub row_idx: Vec<usize>,
    /// `transpose[k]`: value index of the entry mirrored about the diagonal.
    transpose: Vec<usize>,
    /// Value index of each diagonal entry.
    diagonal: Vec<usize>,
}

impl SparsePattern {
    /// Builds the pattern of `nodes` nodes coupled by `elements` (lists of
    /// node indices, already validated to be in range).
    pub fn new<'a>(nodes: usize, elements: impl Iterator<Item = &'a [usize]> + Clone) -> Self {
        let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        for el in elements {
            for &a in el {
                for &b in el {
                    neighbours[b].push(a);
                }
            }
        }
        let mut node_ptr = Vec::with_capacity(nodes + 1);
        let mut node_rows = Vec::new();
        node_ptr.push(0);
        for (b, list) in neighbours.iter_mut().enumerate() {
            list.push(b);
            list.sort_unstable();
            list.dedup();
            node_rows.extend_from_slice(list);
            node_ptr.push(node_rows.len());
        }
        drop(neighbours);
        let ndof = 3 * nodes;
        let mut col_ptr = Vec::with_capacity(ndof + 1);
        let mut row_idx = Vec::with_capacity(9 * node_rows.len());
        col_ptr.push(0);
        for b in 0..nodes {
            let rows = &node_rows[node_ptr[b]..node_ptr[b + 1]];
            for _j in 0..3 {
                for &a in rows {
                    row_idx.extend_from_slice(&[3 * a, 3 * a + 1, 3 * a + 2]);
                }
                col_ptr.push(row_idx.len());
            }
        }
        let mut pattern = Self {
            node_ptr,
            node_rows,
            col_ptr,
            row_idx,
            transpose: Vec::new(),
            diagonal: Vec::new(),
        };
        // Reserved at its length: collected from the flattened columns, it
        // would grow by doubling, holding up to three times its size while
        // it is moved (the largest array of the model's build).
        let mut transpose = Vec::with_capacity(pattern.row_idx.len());
        transpose.extend(
            (0..ndof)
                .flat_map(|c| (pattern.col_ptr[c]..pattern.col_ptr[c + 1]).map(move |k| (c, k)))
                .map(|(c, k)| pattern.find(c, pattern.row_idx[k]).unwrap_or(usize::MAX)),
        );
        pattern.transpose = transpose;
        pattern.diagonal = (0..ndof)
            .map(|d| pattern.find(d, d).unwrap_or(usize::MAX))
            .collect();
        pattern
    }

    /// The pattern of an `nx x ny` grid of squares, each cut into two
    /// triangles (nodes numbered row by row): test matrices of solvers.
    #[cfg(test)]
    pub(crate) fn triangle_grid(nx: usize, ny: usize) -> Self {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut elements = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                elements.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Self::new((nx + 1) * (ny + 1), elements.iter().map(|e| e.as_slice()))
    }

    /// The pattern of an `nx x ny` grid of squares cut into triangles
    /// ([`SparsePattern::triangle_grid`]) widened by couplings two nodes
    /// apart along the rows — as bending's stencils reach beyond a node's
    /// triangles —, and the grid's own pattern, its compact part: test
    /// matrices of the compact preconditioner.
    #[cfg(test)]
    pub(crate) fn wide_grid(nx: usize, ny: usize) -> (Self, Self) {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let (mut triangles, mut wide) = (Vec::new(), Vec::new());
        for j in 0..ny {
            for i in 0..nx {
                triangles.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push(vec![id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                if i + 2 <= nx {
                    wide.push(vec![id(i, j), id(i + 2, j)]);
                }
            }
        }
        let nodes = (nx + 1) * (ny + 1);
        let full = Self::new(nodes, triangles.iter().chain(&wide).map(|e| e.as_slice()));
        let compact = Self::new(nodes, triangles.iter().map(|e| e.as_slice()));
        (full, compact)
    }

    /// Number of rows (= columns).
    pub fn dimension(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Value index of DOF entry `(row, col)`, if stored (binary search; for
    /// set-up, not for hot loops).
    pub fn find(&self, row: usize, col: usize) -> Option<usize> {
        let range = self.col_ptr[col]..self.col_ptr[col + 1];
        self.row_idx[range.clone()]
            .binary_search(&row)
            .ok()
            .map(|k| range.start + k)
    }

    /// Node-graph position of node `a` in column `b`.
    pub fn node_block(&self, a: usize, b: usize) -> Option<usize> {
        let range = self.node_ptr[b]..self.node_ptr[b + 1];
        self.node_rows[range.clone()]
            .binary_search(&a)
            .ok()
            .map(|k| range.start + k)
    }

    /// Value index of entry `(3a + i, 3b + j)` from the node-graph position
    /// `p` of `a` in column `b`.
    #[inline]
    pub fn entry(&self, p: usize, b: usize, i: usize, j: usize) -> usize {
        let (base, stride) = self.block_layout(p, b);
        base + j * stride + i
    }

    /// Where the 3x3 block at node-graph position `p` of column `b` lies
    /// in the values: entry `(i, j)` of the block is at `base + j stride +
    /// i` (the layout of [`SparsePattern::entry`], computed once per block).
    #[inline]
    pub fn block_layout(&self, p: usize, b: usize) -> (usize, usize) {
        block_layout(&self.node_ptr, p, b)
    }

    /// Node-graph CSC: `(ptr, rows)`.
    pub fn node_graph(&self) -> (&[usize], &[usize]) {
        (&self.node_ptr, &self.node_rows)
    }

    /// For each element, its `n x n` node-graph positions `p_ab` (row-major
    /// in `(a, b)`), flattened.
    pub fn element_blocks<'a>(&self, elements: impl Iterator<Item = &'a [usize]>) -> Vec<usize> {
        let mut blocks = Vec::new();
        for el in elements {
            for &a in el {
                for &b in el {
                    blocks.push(self.node_block(a, b).unwrap_or(usize::MAX));
                }
            }
        }
        blocks
    }

    /// Value index of the mirrored entry of value index `k`.
    #[inline]
    pub fn transpose_of(&self, k: usize) -> usize {
        self.transpose[k]
    }

    /// `transpose_of` for every entry.
    pub fn transpose_map(&self) -> &[usize] {
        &self.transpose
    }

    /// Value index of the diagonal entry of DOF `d`.
    #[inline]
    pub fn diagonal_of(&self, d: usize) -> usize {
        self.diagonal[d]
    }

    /// Whether `values` is symmetric to `tolerance` relative to its largest
    /// entry ([`SparsePattern::asymmetry`] `<= tolerance`), stopping at the
    /// first entry that is not.
    pub fn is_symmetric(&self, values: &[f64], tolerance: f64) -> bool {
        // Eight running maxima, by comparisons rather than `f64::max`
        // (whose NaN rule keeps the loop from vectorising): this runs at
        // every Hessian evaluation. A NaN entry then fails the test below.
        let mut lanes = [0.0f64; 8];
        let chunks = values.chunks_exact(8);
        let rest = chunks.remainder();
        for chunk in chunks {
            for (m, v) in lanes.iter_mut().zip(chunk) {
                let a = v.abs();
                *m = if a > *m { a } else { *m };
            }
        }
        let max = lanes
            .iter()
            .chain(rest)
            .fold(0.0f64, |m, v| if v.abs() > m { v.abs() } else { m });
        let bound = tolerance * max;
        values
            .iter()
            .zip(&self.transpose)
            .all(|(v, &t)| (v - values[t]).abs() <= bound)
    }

    /// Largest `|A_ij - A_ji|` relative to the largest `|A_ij|` (0 for a
    /// zero matrix).
    pub fn asymmetry(&self, values: &[f64]) -> f64 {
        let mut max = 0.0f64;
        let mut diff = 0.0f64;
        for (k, v) in values.iter().enumerate() {
            max = max.max(v.abs());
            diff = diff.max((v - values[self.transpose[k]]).abs());
        }
        if max > 0.0 { diff / max } else { 0.0 }
    }
}

/// The elements incident to each of `nodes` nodes, in CSR form `(ptr,
/// incident)`: node `a`'s are `incident[ptr[a]..ptr[a + 1]]`, in order.
fn incidence<'a>(
    nodes: usize,
    elements: impl Iterator<Item = &'a [usize]> + Clone,
) -> (Vec<usize>, Vec<usize>) {
    let mut ptr = vec![0usize; nodes + 1];
    for el in elements.clone() {
        for &a in el {
            ptr[a + 1] += 1;
        }
    }
    for i in 0..nodes {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut incident = vec![0usize; ptr[nodes]];
    for (e, el) in elements.enumerate() {
        for &a in el {
            incident[fill[a]] = e;
            fill[a] += 1;
        }
    }
    (ptr, incident)
}

/// The number of 3x3 node blocks — the node graph's entries, diagonal
/// included — that [`SparsePattern::new`] would store for the same
/// arguments, counted without building it: the node-element incidence and
/// one mark a node (`O(nodes + sum of stencil sizes)` words, against the
/// pattern's 27 words a block). The memory a pattern needs is known from it
/// before the pattern is allocated (`crate::memory::pattern_estimate`).
pub fn block_count<'a>(nodes: usize, elements: impl Iterator<Item = &'a [usize]> + Clone) -> usize {
    let stencils: Vec<&[usize]> = elements.clone().collect();
    let (ptr, incident) = incidence(nodes, elements);
    // mark[a] == b: node a is counted in column b already.
    let mut mark = vec![usize::MAX; nodes];
    let mut blocks = 0;
    for b in 0..nodes {
        // The diagonal block, there even for a node of no element.
        mark[b] = b;
        blocks += 1;
        for &e in &incident[ptr[b]..ptr[b + 1]] {
            for &a in stencils[e] {
                if mark[a] != b {
                    mark[a] = b;
                    blocks += 1;
                }
            }
        }
    }
    blocks
}

/// Greedy colouring of elements so that no two elements of one colour share
/// a node: the elements of one colour can be assembled in parallel without
/// write conflicts.
pub fn colour_elements<'a>(
    nodes: usize,
    elements: impl Iterator<Item = &'a [usize]> + Clone,
) -> Vec<Vec<usize>> {
    let count = elements.clone().count();
    let (ptr, incident) = incidence(nodes, elements.clone());
    let mut colour = vec![usize::MAX; count];
    let mut used: Vec<usize> = Vec::new(); // used[c] == e marks colour c taken for element e
    let mut colours: Vec<Vec<usize>> = Vec::new();
    for (e, el) in elements.enumerate() {
        for &a in el {
            for &other in &incident[ptr[a]..ptr[a + 1]] {
                let c = colour[other];
                if c != usize::MAX {
                    used[c] = e;
                }
            }
        }
        let c = (0..colours.len())
            .find(|&c| used[c] != e)
            .unwrap_or(colours.len());
        if c == colours.len() {
            colours.push(Vec::new());
            used.push(usize::MAX);
        }
        colour[e] = c;
        colours[c].push(e);
    }
    colours
}

/// The 3x3 block of scalar CSC `values` whose entry `(0, 0)` is at `base`,
/// with its columns `stride` apart (the layout of
/// [`SparsePattern`]: rows of a block are consecutive).
#[inline(always)]
pub(crate) fn gather_block(values: &[f64], base: usize, stride: usize) -> Block {
    let (b, t) = (base, stride);
    [
        values[b],
        values[b + t],
        values[b + 2 * t],
        values[b + 1],
        values[b + 1 + t],
        values[b + 1 + 2 * t],
        values[b + 2],
        values[b + 2 + t],
        values[b + 2 + 2 * t],
    ]
}

/// On meshes of [`crate::model::PARALLEL_ABOVE`] elements or more, the
/// assembly splits the mesh until each part has fewer elements (or bending
/// patches) than this, and adds each part up on one thread: 2,048 T3
/// patches touch about a thousand nodes, whose Hessian columns (with
/// bending, ~1.4 kB each) fit in a core's L2 cache (docs/performance.md,
/// "Assembly in cache-sized parts").
pub const ASSEMBLY_LEAF: usize = 2048;

/// The assembly order: stencils (elements, bending patches) `first` and
/// `second` share no node, so two threads can add them up at once; the
/// `interface` stencils, which touch nodes of both, follow by colour, each
/// colour in two halves. A side is a list in index order or, on a large
/// mesh, split again the same way ([`Halves::nested`]): a nested
/// dissection of the stencils, whose leaves are contiguous patches of the
/// mesh. Each leaf's Hessian columns stay in cache while it is added up,
/// where a colour's stencils, spread over the whole mesh and sharing no
/// node, touch every column once per colour (docs/performance.md,
/// "Assembly in cache-sized parts").
#[derive(Debug, Clone)]
pub(crate) struct Halves {
    pub(crate) first: Part,
    pub(crate) second: Part,
    pub(crate) interface: Vec<Vec<usize>>,
    /// Run the halves on rayon's pool ([`Halves::nested`]) rather than on
    /// [`crate::par`]'s helper ([`Halves::of`]).
    rayon: bool,
}

/// One side of a [`Halves`] split.
#[derive(Debug, Clone)]
pub(crate) enum Part {
    /// The stencils, in index order, added up on one thread.
    Leaf(Vec<usize>),
    /// Split again.
    Split(Box<Halves>),
}

/// A stencil set being split: the stencils and their colours.
struct Stencils<'n, 's> {
    nodes: &'n [[f64; 3]],
    list: Vec<&'s [usize]>,
    colour: Vec<usize>,
    colours: usize,
    /// Per node, the sides of the split at hand that touch it (bit 0:
    /// first, bit 1: second); zero between splits, so that a split costs
    /// its own stencils, not the mesh's nodes.
    touched: std::cell::RefCell<Vec<u8>>,
}

impl Halves {
    /// Splits the stencils (node lists: elements, bending patches) on
    /// nodes at `nodes`, coloured by `colours`, at the median of their
    /// centroids along the nodes' longest extent; a stencil touching a
    /// node that stencils of both sides touch goes to the interface. The
    /// small-mesh order: one split, each half on one of two threads
    /// ([`crate::par::join`]).
    pub(crate) fn of<'a>(
        nodes: &[[f64; 3]],
        stencils: impl Iterator<Item = &'a [usize]> + Clone,
        colours: &[Vec<usize>],
    ) -> Self {
        Self::build(nodes, stencils, colours, usize::MAX, false)
    }

    /// As [`Halves::of`], each side with `leaf` stencils or more split
    /// again (along its own longest extent), the halves run on rayon's
    /// pool ([`rayon::join`]): the large-mesh order. `leaf` is at least 2.
    pub(crate) fn nested<'a>(
        nodes: &[[f64; 3]],
        stencils: impl Iterator<Item = &'a [usize]> + Clone,
        colours: &[Vec<usize>],
        leaf: usize,
    ) -> Self {
        Self::build(nodes, stencils, colours, leaf.max(2), true)
    }

    fn build<'a>(
        nodes: &[[f64; 3]],
        stencils: impl Iterator<Item = &'a [usize]> + Clone,
        colours: &[Vec<usize>],
        leaf: usize,
        rayon: bool,
    ) -> Self {
        let list: Vec<&[usize]> = stencils.collect();
        let mut colour = vec![0; list.len()];
        for (c, members) in colours.iter().enumerate() {
            for &e in members {
                colour[e] = c;
            }
        }
        let set = Stencils {
            nodes,
            list,
            colour,
            colours: colours.len(),
            touched: std::cell::RefCell::new(vec![0; nodes.len()]),
        };
        let all: Vec<usize> = (0..set.list.len()).collect();
        // The whole mesh is split along the extent of all its nodes.
        let mut extent = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for x in nodes {
            for i in 0..3 {
                extent.0[i] = extent.0[i].min(x[i]);
                extent.1[i] = extent.1[i].max(x[i]);
            }
        }
        Self::split(&set, &all, extent, leaf, rayon)
    }

    /// Splits `subset` (stencil indices, increasing) along the longest
    /// side of the box `extent`.
    fn split(
        set: &Stencils,
        subset: &[usize],
        extent: ([f64; 3], [f64; 3]),
        leaf: usize,
        rayon: bool,
    ) -> Self {
        let centroid = |e: usize| {
            let el = set.list[e];
            let mut c = [0.0; 3];
            for &a in el {
                for i in 0..3 {
                    c[i] += set.nodes[a][i] / el.len() as f64;
                }
            }
            c
        };
        let centroids: Vec<[f64; 3]> = subset.iter().map(|&e| centroid(e)).collect();
        let count = subset.len();
        let (lo, hi) = extent;
        let axis = (0..3)
            .max_by(|&i, &j| (hi[i] - lo[i]).total_cmp(&(hi[j] - lo[j])))
            .unwrap_or(0);
        let mut by_position: Vec<usize> = (0..count).collect();
        by_position.sort_by(|&a, &b| {
            centroids[a][axis]
                .total_cmp(&centroids[b][axis])
                .then(a.cmp(&b))
        });
        let mut side = vec![0u8; count];
        for &k in &by_position[count / 2..] {
            side[k] = 1;
        }
        let at_interface: Vec<bool> = {
            let mut touched = set.touched.borrow_mut();
            for (k, &e) in subset.iter().enumerate() {
                for &a in set.list[e] {
                    touched[a] |= 1 << side[k];
                }
            }
            let flags = subset
                .iter()
                .map(|&e| set.list[e].iter().any(|&a| touched[a] == 3))
                .collect();
            for &e in subset {
                for &a in set.list[e] {
                    touched[a] = 0;
                }
            }
            flags
        };
        let (mut first, mut second) = (Vec::new(), Vec::new());
        let mut interface = vec![Vec::new(); set.colours];
        for (k, &e) in subset.iter().enumerate() {
            if at_interface[k] {
                interface[set.colour[e]].push(e);
            } else if side[k] == 0 {
                first.push(e);
            } else {
                second.push(e);
            }
        }
        interface.retain(|c| !c.is_empty());
        let part = |members: Vec<usize>| {
            if members.len() < leaf {
                return Part::Leaf(members);
            }
            let mut extent = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &e in &members {
                for &a in set.list[e] {
                    for i in 0..3 {
                        extent.0[i] = extent.0[i].min(set.nodes[a][i]);
                        extent.1[i] = extent.1[i].max(set.nodes[a][i]);
                    }
                }
            }
            Part::Split(Box::new(Self::split(set, &members, extent, leaf, rayon)))
        };
        Self {
            first: part(first),
            second: part(second),
            interface,
            rayon,
        }
    }

    /// Every stencil, in the assembly's order: the first side's, the
    /// second's, then the interface's by colour.
    pub(crate) fn order(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        Box::new(
            self.first
                .order()
                .chain(self.second.order())
                .chain(self.interface.iter().flatten().copied()),
        )
    }

    /// The sum of `work` over lists of stencils that together hold each
    /// once, in [`Halves::order`]: the two sides at once (on two threads
    /// where there are), then each interface colour in two halves at
    /// once. Lists that run at once share no node. The sum is added up in
    /// a fixed order: it depends neither on the threads nor on how they
    /// were scheduled.
    pub(crate) fn run(&self, work: &(impl Fn(&[usize]) -> f64 + Sync)) -> f64 {
        let (a, b) = self.join(|| self.first.run(work), || self.second.run(work));
        let mut sum = a + b;
        for c in &self.interface {
            let (x, y) = c.split_at(c.len() / 2);
            let (a, b) = self.join(|| work(x), || work(y));
            sum += a + b;
        }
        sum
    }

    fn join(&self, a: impl FnOnce() -> f64 + Send, b: impl FnOnce() -> f64 + Send) -> (f64, f64) {
        if self.rayon {
            rayon::join(a, b)
        } else {
            crate::par::join(a, b)
        }
    }

    /// How deep the splits go (1: one split).
    #[cfg(test)]
    pub(crate) fn depth(&self) -> usize {
        1 + self.first.depth().max(self.second.depth())
    }
}

impl Part {
    /// The part's stencils, in the assembly's order.
    pub(crate) fn order(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        match self {
            Part::Leaf(list) => Box::new(list.iter().copied()),
            Part::Split(halves) => halves.order(),
        }
    }

    /// How many stencils the part holds.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.order().count()
    }

    fn run(&self, work: &(impl Fn(&[usize]) -> f64 + Sync)) -> f64 {
        match self {
            Part::Leaf(list) => work(list),
            Part::Split(halves) => halves.run(work),
        }
    }

    #[cfg(test)]
    fn depth(&self) -> usize {
        match self {
            Part::Leaf(_) => 0,
            Part::Split(halves) => halves.depth(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_formula_matches_search_and_transpose_is_an_involution() {
        let elements = [vec![0usize, 1, 2], vec![1, 3, 2], vec![3, 4, 2]];
        let p = SparsePattern::new(5, elements.iter().map(|e| e.as_slice()));
        for el in &elements {
            for &a in el {
                for &b in el {
                    let pb = p.node_block(a, b).unwrap();
                    for i in 0..3 {
                        for j in 0..3 {
                            assert_eq!(Some(p.entry(pb, b, i, j)), p.find(3 * a + i, 3 * b + j));
                        }
                    }
                }
            }
        }
        for k in 0..p.nnz() {
            assert_eq!(p.transpose_of(p.transpose_of(k)), k);
        }
        assert_eq!(p.find(0, 12), None);
    }

    /// The count of blocks without the pattern is the pattern's: a mesh
    /// with a node of no element, the membrane's elements of every order,
    /// and with bending's stencils chained to them.
    #[test]
    fn block_count_is_the_patterns_block_count() {
        let elements = [vec![0usize, 1, 2], vec![1, 3, 2], vec![3, 4, 2]];
        let iter = || elements.iter().map(|e| e.as_slice());
        let with_orphan = SparsePattern::new(6, iter());
        assert_eq!(block_count(6, iter()), with_orphan.node_graph().1.len());
        for order in [
            crate::mesh::ElementOrder::Linear,
            crate::mesh::ElementOrder::Quadratic,
            crate::mesh::ElementOrder::Cubic,
        ] {
            let mesh = crate::mesh::generate::rectangle(
                [1.0, 1.0],
                [7, 5],
                crate::mesh::generate::Pattern::Alternate,
                [0.0; 3],
                order,
            );
            let n = mesh.node_count();
            let membrane = SparsePattern::new(n, mesh.elements());
            assert_eq!(
                block_count(n, mesh.elements()),
                membrane.node_graph().1.len()
            );
            let (ptr, nodes) = crate::bending::stencils_of(&mesh).unwrap();
            let stencils = || ptr.windows(2).map(|w| &nodes[w[0]..w[1]]);
            let bending = SparsePattern::new(n, mesh.elements().chain(stencils()));
            let blocks = block_count(n, mesh.elements().chain(stencils()));
            assert_eq!(blocks, bending.node_graph().1.len());
            assert!(blocks > membrane.node_graph().1.len(), "{order:?}");
        }
    }

    #[test]
    fn colours_never_share_a_node() {
        let mesh = crate::mesh::generate::rectangle(
            [1.0, 1.0],
            [7, 5],
            crate::mesh::generate::Pattern::Alternate,
            [0.0; 3],
            crate::mesh::ElementOrder::Quadratic,
        );
        let colours = colour_elements(mesh.node_count(), mesh.elements());
        let total: usize = colours.iter().map(Vec::len).sum();
        assert_eq!(total, mesh.element_count());
        for c in &colours {
            let mut seen = vec![false; mesh.node_count()];
            for &e in c {
                for &a in mesh.element(e) {
                    assert!(!seen[a]);
                    seen[a] = true;
                }
            }
        }
    }
}
