//! Parallel assembly of the internal forces and the Hessian, and of the
//! follower pressure's forces and tangent.
//!
//! Elements are processed in two halves of the mesh that share no node, on
//! two threads, then the elements between them colour by colour (no two
//! elements of a colour share a node); from [`super::PARALLEL_ABOVE`]
//! elements on, each half is split again, down to parts of fewer than
//! [`crate::solver::pattern::ASSEMBLY_LEAF`] elements, on rayon's pool
//! ([`crate::solver::pattern::Halves`]). An element writes only the force entries of its own
//! nodes and the Hessian entries of its own node pairs, so the writes of
//! elements that run at once never overlap. Each Hessian block's first
//! element in that order writes it and the others add: the Hessian is not
//! zeroed first.

use super::Model;
use crate::element::membrane::{
    element_force_hessian_or_zero, element_stress_state, principal_values,
};
use crate::load::pressure::add_pressure_force;
use crate::mesh::lagrange::MAX_NODES;
use crate::par::Shared;
use rayon::prelude::*;

/// Adds (or, for a block's first element, writes) the element Hessian `k`
/// (row-major, `3N x 3N`) of an element with nodes `el` into the Hessian
/// values behind `h`; `zero`: the element Hessian is zero (`k` is not
/// read), and only the blocks the element is first in are written, with
/// zeros. Block `(a, b)` starts at `bases[N a + b]`, its
/// entry `(i, j)` at `+ j stride_b + i`. With `N` known the loops unroll
/// and `k`'s indices are constants.
///
/// # Safety (of the writes through `h`)
/// No other thread writes the same entries meanwhile (elements that run
/// at once share no node: see the module docs).
#[inline(always)]
fn scatter<const N: usize>(
    model: &Model,
    h: Shared,
    el: &[usize],
    k: &[f64],
    bases: &[usize],
    first: &[bool],
    zero: bool,
) {
    let k: &[f64] = &k[..9 * N * N];
    let (ptr, _) = model.pattern.node_graph();
    for b in 0..N {
        let node_b = el[b];
        let stride = 3 * (ptr[node_b + 1] - ptr[node_b]);
        for a in 0..N {
            let base = bases[a * N + b];
            if zero && !first[a * N + b] {
                continue;
            }
            let block: [f64; 9] = if zero {
                [0.0; 9]
            } else {
                std::array::from_fn(|ij| k[(3 * a + ij % 3) * 3 * N + 3 * b + ij / 3])
            };
            // SAFETY: see the function's docs; the indices are those of
            // the pattern's block (a, b).
            unsafe {
                if first[a * N + b] {
                    for (ij, v) in block.iter().enumerate() {
                        h.set(base + (ij / 3) * stride + ij % 3, *v);
                    }
                } else {
                    for (ij, v) in block.iter().enumerate() {
                        h.add(base + (ij / 3) * stride + ij % 3, *v);
                    }
                }
            }
        }
    }
}

/// Elements per parallel work item.
const CHUNK: usize = 256;

/// Principal stresses below this (Pa) count as zero in the reported
/// wrinkling state (round-off of an unstressed fabric is ~1e-9 Pa; fabric
/// stresses are 1e1 to 1e6 Pa).
const UNSTRESSED: f64 = 1e-3;

/// Per-thread scratch for one element, on the stack (no allocation per
/// assembly).
struct Local {
    y: [[f64; 3]; MAX_NODES],
    f: [f64; 3 * MAX_NODES],
    fp: [f64; 3 * MAX_NODES],
    k: [f64; 9 * MAX_NODES * MAX_NODES],
}

impl Local {
    fn new() -> Self {
        Self {
            y: [[0.0; 3]; MAX_NODES],
            f: [0.0; 3 * MAX_NODES],
            fp: [0.0; 3 * MAX_NODES],
            k: [0.0; 9 * MAX_NODES * MAX_NODES],
        }
    }
}

/// Per-element results for output.
#[derive(Debug, Clone, Default)]
pub struct ElementResults {
    /// Mean second Piola–Kirchhoff stress `[S11, S22, S12]` (Pa) in the element's local frame.
    pub stress: Vec<[f64; 3]>,
    /// Principal values `[s1, s2]`, `s1 >= s2` (Pa).
    pub principal: Vec<[f64; 2]>,
    /// Wrinkling state: 0 taut, 1 wrinkled, 2 slack — the material's at
    /// the mean strain, or (for a material that carries compression) the
    /// classification of the stress' principal values; an element whose
    /// principal stresses are both below 1 mPa is reported slack.
    pub state: Vec<i32>,
}

impl ElementResults {
    /// Fractions of taut, wrinkled and slack elements.
    pub fn state_fractions(&self) -> [f64; 3] {
        let mut count = [0usize; 3];
        for &s in &self.state {
            count[s.clamp(0, 2) as usize] += 1;
        }
        let n = self.state.len().max(1) as f64;
        count.map(|c| c as f64 / n)
    }
}

impl Model {
    /// Current positions of element `e`'s nodes (the first
    /// `nodes_per_element` entries).
    #[inline]
    fn element_positions(&self, e: usize, y: &[f64]) -> [[f64; 3]; MAX_NODES] {
        let mut ye = [[0.0; 3]; MAX_NODES];
        for (a, &node) in self.mesh.element(e).iter().enumerate() {
            ye[a] = [y[3 * node], y[3 * node + 1], y[3 * node + 2]];
        }
        ye
    }

    /// Strain energy (returned), internal forces `f_int` (overwritten)
    /// and, if given, the Hessian values `h` (overwritten) `K` on
    /// [`Model::pattern`]. `y`: current positions, flattened.
    pub fn assemble(&self, y: &[f64], f_int: &mut [f64], h: Option<&mut [f64]>) -> f64 {
        self.assemble_projected(y, f_int, h, None)
    }

    /// [`Model::assemble`], with the Hessian of every element that has a
    /// node flagged in `project` (one flag per node) replaced by its
    /// positive semi-definite part ([`crate::psd`]) before it is added:
    /// the projected Newton's Hessian (`solver::newton`). `None`, or no
    /// flag set: the exact Hessian, to the bit.
    pub fn assemble_projected(
        &self,
        y: &[f64],
        f_int: &mut [f64],
        h: Option<&mut [f64]>,
        project: Option<&[bool]>,
    ) -> f64 {
        let n = self.mesh.order.nodes_per_element();
        let m = 3 * n;
        f_int.fill(0.0);
        let want_h = h.is_some();
        let h_ptr = match h {
            Some(h) => {
                // Not zeroed: each block's first element (in the colour
                // order) writes it, the others add; blocks no element
                // reaches are zeroed here.
                for &(base, stride) in &self.untouched_blocks {
                    for j in 0..3 {
                        h[base + j * stride..base + j * stride + 3].fill(0.0);
                    }
                }
                Shared(h.as_mut_ptr())
            }
            None => Shared(std::ptr::null_mut()),
        };
        let fi = Shared(f_int.as_mut_ptr());
        let material = self.material.as_ref();
        // Elements are summed in fixed groups and chunks, their partial
        // energies in order: the result depends neither on how rayon
        // schedules the work nor on the number of threads (resumed runs
        // reproduce uninterrupted ones to the bit).
        let work = |local: &mut Local, chunk: &[usize]| -> f64 {
            let mut sum = 0.0;
            for &e in chunk {
                let el = self.mesh.element(e);
                for (a, &node) in el.iter().enumerate() {
                    local.y[a] = [y[3 * node], y[3 * node + 1], y[3 * node + 2]];
                }
                let (grad, weight) = self.geometry.element(e);
                let k = want_h.then_some(&mut local.k[..m * m]);
                let (u, zero) = element_force_hessian_or_zero(
                    material,
                    self.section,
                    &local.y[..n],
                    grad,
                    weight,
                    &mut local.f[..m],
                    k,
                );
                if want_h && !zero && project.is_some_and(|flags| el.iter().any(|&a| flags[a])) {
                    crate::psd::project(&mut local.k[..m * m], m, m);
                }
                // SAFETY: elements that run at once (of one colour, or of
                // the two halves of a small mesh) share no node, so the
                // entries written below are disjoint across threads.
                unsafe {
                    for (a, &node) in el.iter().enumerate() {
                        for i in 0..3 {
                            fi.add(3 * node + i, local.f[3 * a + i]);
                        }
                    }
                    if want_h {
                        let bases = &self.element_blocks[e * n * n..(e + 1) * n * n];
                        let first = &self.element_block_first[e * n * n..(e + 1) * n * n];
                        let k = &local.k[..m * m];
                        // A zero element Hessian only writes zeros into
                        // the blocks it is first in (`k` is then not read:
                        // the kernel left it unwritten).
                        match n {
                            3 => scatter::<3>(self, h_ptr, el, k, bases, first, zero),
                            6 => scatter::<6>(self, h_ptr, el, k, bases, first, zero),
                            _ => scatter::<10>(self, h_ptr, el, k, bases, first, zero),
                        }
                    }
                }
                sum += u;
            }
            sum
        };
        self.traverse(work)
    }

    /// Runs `work` over every element in the assembly's order and returns
    /// the sum of its results (in a fixed order: the result depends
    /// neither on the threads nor on rayon's scheduling). Elements that
    /// run at once share no node, so `work` may write the entries of its
    /// elements' nodes without locks. The order is [`Model`]'s `halves`:
    /// two halves of the mesh, the second on the helper thread
    /// (`crate::par`: rayon's wake-ups cost more than a small mesh's
    /// loop), then the elements at their interface, each colour in two
    /// halves; from [`super::PARALLEL_ABOVE`] elements on, each half split
    /// again into parts of fewer than [`crate::solver::pattern::ASSEMBLY_LEAF`] elements,
    /// on rayon's pool. Each thread's scratch is kept between assemblies
    /// (7 kB to zero otherwise).
    fn traverse(&self, work: impl Fn(&mut Local, &[usize]) -> f64 + Sync) -> f64 {
        thread_local! {
            static LOCAL: std::cell::RefCell<Local> = std::cell::RefCell::new(Local::new());
        }
        self.halves
            .run(&|part: &[usize]| LOCAL.with(|l| work(&mut l.borrow_mut(), part)))
    }

    /// Adds the follower pressure forces for the pressure `pressure` (Pa)
    /// to `f_ext` and, if given, their derivative `-d f_p / d Y` to the
    /// Hessian values `h` on [`Model::pattern`] (docs/theory.md §1.5; the kernel is
    /// [`add_pressure_force`]). The forces are added element by element in
    /// the order of [`Model::assemble`], so `f_ext` gets the same sums.
    pub fn add_pressure(&self, y: &[f64], pressure: f64, f_ext: &mut [f64], h: Option<&mut [f64]>) {
        if pressure == 0.0 {
            return;
        }
        let n = self.mesh.order.nodes_per_element();
        let m = 3 * n;
        let want_h = h.is_some();
        let h_ptr = Shared(h.map_or(std::ptr::null_mut(), |h| h.as_mut_ptr()));
        let fe = Shared(f_ext.as_mut_ptr());
        // Every block is added to (none is written first).
        const ADD: [bool; MAX_NODES * MAX_NODES] = [false; MAX_NODES * MAX_NODES];
        let work = |local: &mut Local, chunk: &[usize]| -> f64 {
            for &e in chunk {
                let el = self.mesh.element(e);
                for (a, &node) in el.iter().enumerate() {
                    local.y[a] = [y[3 * node], y[3 * node + 1], y[3 * node + 2]];
                }
                local.fp[..m].fill(0.0);
                if want_h {
                    local.k[..m * m].fill(0.0);
                }
                let k = want_h.then_some(&mut local.k[..m * m]);
                add_pressure_force(
                    pressure,
                    &local.y[..n],
                    &self.pressure_quadrature,
                    &mut local.fp[..m],
                    k,
                    -1.0,
                );
                // SAFETY: elements that run at once share no node (see
                // `traverse`), so the entries written are disjoint.
                unsafe {
                    for (a, &node) in el.iter().enumerate() {
                        for i in 0..3 {
                            fe.add(3 * node + i, local.fp[3 * a + i]);
                        }
                    }
                }
                if want_h {
                    let bases = &self.element_blocks[e * n * n..(e + 1) * n * n];
                    let k = &local.k[..m * m];
                    let first = &ADD[..n * n];
                    match n {
                        3 => scatter::<3>(self, h_ptr, el, k, bases, first, false),
                        6 => scatter::<6>(self, h_ptr, el, k, bases, first, false),
                        _ => scatter::<10>(self, h_ptr, el, k, bases, first, false),
                    }
                }
            }
            0.0
        };
        self.traverse(work);
    }

    /// Strain energy only (J), summed deterministically.
    pub fn strain_energy(&self, y: &[f64]) -> f64 {
        let n = self.mesh.order.nodes_per_element();
        let count = self.mesh.element_count();
        let chunk = |c: usize| {
            (c * CHUNK..((c + 1) * CHUNK).min(count))
                .map(|e| {
                    let ye = self.element_positions(e, y);
                    let (grad, weight) = self.geometry.element(e);
                    crate::element::membrane::element_energy(
                        self.material.as_ref(),
                        self.section,
                        &ye[..n],
                        grad,
                        weight,
                    )
                })
                .sum::<f64>()
        };
        let chunks = 0..count.div_ceil(CHUNK);
        if self.parallel() {
            chunks
                .into_par_iter()
                .map(chunk)
                .collect::<Vec<f64>>()
                .iter()
                .sum()
        } else {
            chunks.map(chunk).sum()
        }
    }

    /// Fractions of taut, wrinkled and slack elements at positions `y`
    /// (as [`ElementResults::state_fractions`], without storing the
    /// per-element results).
    pub fn state_fractions(&self, y: &[f64]) -> [f64; 3] {
        let counts = self.fold_elements(
            [0; 3],
            |mut count, e| {
                count[self.element_result(e, y).2.clamp(0, 2) as usize] += 1;
                count
            },
            add_counts,
        );
        self.fractions(counts)
    }

    /// `counts` of taut, wrinkled and slack elements as fractions.
    fn fractions(&self, counts: [usize; 3]) -> [f64; 3] {
        let n = self.mesh.element_count().max(1) as f64;
        counts.map(|c| c as f64 / n)
    }

    /// `visit` folded over the elements from `start`, the partial results
    /// joined by `join`: in two halves of the elements on two threads
    /// ([`crate::par`]), or for large meshes on rayon's pool. `join` must
    /// not depend on how the elements were split (a sum of counts, the
    /// first of the smallest values) for the result not to.
    fn fold_elements<T: Copy + Send + Sync>(
        &self,
        start: T,
        visit: impl Fn(T, usize) -> T + Sync + Send,
        join: impl Fn(T, T) -> T + Sync + Send,
    ) -> T {
        let elements = 0..self.mesh.element_count();
        if self.parallel() {
            elements
                .into_par_iter()
                .fold(|| start, &visit)
                .reduce(|| start, &join)
        } else {
            let (a, b) = crate::par::halves(elements.len(), |r| r.fold(start, &visit));
            join(a, b)
        }
    }

    /// Mean stress, principal stresses and wrinkling state of element `e`.
    fn element_result(&self, e: usize, y: &[f64]) -> ([f64; 3], [f64; 2], i32) {
        self.element_result_at(e, &self.element_positions(e, y))
    }

    /// [`Model::element_result`] with element `e`'s node positions `ye`.
    fn element_result_at(&self, e: usize, ye: &[[f64; 3]]) -> ([f64; 3], [f64; 2], i32) {
        let n = self.mesh.order.nodes_per_element();
        let (grad, weight) = self.geometry.element(e);
        let (s, _, wrinkle_state) =
            element_stress_state(self.material.as_ref(), self.section, &ye[..n], grad, weight);
        let (s1, s2) = principal_values(s);
        // An unstressed element (a fabric in free fall) is slack,
        // whatever the round-off in its stress says.
        let state = if s1.abs().max(s2.abs()) < UNSTRESSED {
            2
        } else {
            match wrinkle_state {
                Some(state) => state as i32,
                None if s2 >= 0.0 => 0,
                None if s1 > 0.0 => 1,
                None => 2,
            }
        };
        (s, [s1, s2], state)
    }

    /// Mean stress and principal stresses of every element at positions `y`.
    pub fn element_results(&self, y: &[f64]) -> ElementResults {
        let result = |e: usize| self.element_result(e, y);
        let elements = 0..self.mesh.element_count();
        let per_element: Vec<([f64; 3], [f64; 2], i32)> = if self.parallel() {
            elements.into_par_iter().map(result).collect()
        } else {
            let (mut a, b) =
                crate::par::halves(elements.len(), |r| r.map(result).collect::<Vec<_>>());
            a.extend(b);
            a
        };
        ElementResults {
            stress: per_element.iter().map(|r| r.0).collect(),
            principal: per_element.iter().map(|r| r.1).collect(),
            state: per_element.iter().map(|r| r.2).collect(),
        }
    }
}

impl Model {
    /// Smallest principal stretch over all quadrature points, `sqrt` of the
    /// smallest eigenvalue of `C = F^T F`, and the element where it occurs.
    pub fn min_stretch(&self, y: &[f64]) -> (f64, usize) {
        self.fold_elements(
            (f64::INFINITY, 0),
            |least, e| {
                let stretch = self.least_stretch_at(e, &self.element_positions(e, y));
                smaller_stretch(least, (stretch, e))
            },
            smaller_stretch,
        )
    }

    /// The elements whose smallest principal stretch (over their
    /// quadrature points, as [`Model::min_stretch`]) is below `floor` at
    /// `y`, in order.
    pub fn elements_compressed_below(&self, y: &[f64], floor: f64) -> Vec<usize> {
        (0..self.mesh.element_count())
            .filter(|&e| self.least_stretch_at(e, &self.element_positions(e, y)) < floor)
            .collect()
    }

    /// The smallest principal stretch over element `e`'s quadrature points,
    /// its nodes at `ye`.
    fn least_stretch_at(&self, e: usize, ye: &[[f64; 3]]) -> f64 {
        let n = self.mesh.order.nodes_per_element();
        let (grad, weight) = self.geometry.element(e);
        let mut least = f64::INFINITY;
        for q in 0..weight.len() {
            let f =
                crate::element::membrane::deformation_gradient(&ye[..n], &grad[q * n..(q + 1) * n]);
            let e2 = crate::element::membrane::green_lagrange(&f);
            // C = I + 2E; its smallest eigenvalue from E's.
            let (_, e_min) = principal_values([e2[0], e2[1], 0.5 * e2[2]]);
            least = least.min((1.0 + 2.0 * e_min).max(0.0).sqrt());
        }
        least
    }

    /// [`Model::min_stretch`] and [`Model::state_fractions`] in one pass
    /// over the elements (the run loop's per-step statistics), the same
    /// values.
    pub fn stretch_and_states(&self, y: &[f64]) -> ((f64, usize), [f64; 3]) {
        let (least, counts) = self.fold_elements(
            ((f64::INFINITY, 0), [0; 3]),
            |(least, mut count), e| {
                let ye = self.element_positions(e, y);
                count[self.element_result_at(e, &ye).2.clamp(0, 2) as usize] += 1;
                let stretch = self.least_stretch_at(e, &ye);
                (smaller_stretch(least, (stretch, e)), count)
            },
            |(la, ca), (lb, cb)| (smaller_stretch(la, lb), add_counts(ca, cb)),
        );
        (least, self.fractions(counts))
    }
}

/// Element counts per state, summed.
fn add_counts(a: [usize; 3], b: [usize; 3]) -> [usize; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The smaller stretch of two `(stretch, element)`; the first on ties.
fn smaller_stretch(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    if b.0 < a.0 { b } else { a }
}
