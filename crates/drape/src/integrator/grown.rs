//! The Hessian's layout grown with self-contact's pairs (issue 33,
//! ARCHITECTURE.md "The Hessian's layout"). The model's pattern — the
//! elements' and the bending stencils' couplings — is fixed when the model
//! is built; self-contact couples nodes of folds and plies that meet
//! anywhere. The stepper owns a second layout, the model's pattern with
//! the four-node stencils of the pairs that may touch added, and a linear
//! solver bound to it:
//!
//! - **when it is rebuilt**: at the start of each step, from the broad
//!   phase at the step's first guess with the distance `2 d̂`. If every
//!   coupling those pairs need is in the layout already, nothing happens;
//!   otherwise the layout is rebuilt with the pairs within [`ROOM`] times
//!   that distance (those near now: it follows the contacts), and the
//!   solver's symbolic analysis is done again. Pairs that come within `d̂`
//!   during the step from farther are held by the diagonal treatment
//!   until the next step's layout takes them in.
//! - **how the step writes it**: the terms still assemble on the model's
//!   pattern (their block positions are computed once), into
//!   [`Grown::model_values`]; the supports are applied there; then the
//!   values are copied through [`Grown::map`] into the grown layout, and
//!   self-contact's pair Hessians are added on it, leaving out the held
//!   degrees of freedom. A pair that appears within a step without its
//!   stencil in the layout falls back to the diagonal treatment of
//!   [`crate::contact::self_contact`].
//! - **with multipliers** their elimination (rotating the rows and
//!   columns of the nodes held on an obstacle) runs on the grown layout,
//!   after the pairs' couplings are in.
//! - **where it is not used**: with a linear mode other than `direct`
//!   (the kept multigrid hierarchy and `reuse`'s factor are made for the
//!   model's pattern); those keep the diagonal treatment.
//!
//! A checkpoint keeps the stencils the layout was built from (format 7),
//! and a resumed run builds the same layout from them
//! ([`restore`]): it factorises on the same pattern as the uninterrupted
//! run, and ends with the same bytes (tests/self_contact.rs).

use crate::model::Model;
use crate::solver::newton::NewtonWorkspace;
use crate::solver::{LinearMode, LinearSolveError, LinearSolver, SparsePattern};
use std::collections::HashSet;

/// The pairs whose couplings a step's layout must hold: those within
/// `TRIGGER d̂` at the step's first guess.
const TRIGGER: f64 = 2.0;

/// How much farther than [`TRIGGER`] a rebuilt layout takes pairs in
/// (module docs): the room that makes it rebuild rarely.
const ROOM: f64 = 3.0;

/// The grown layout (module docs).
#[derive(Debug)]
pub struct Grown {
    /// The model's pattern with the pairs' stencils.
    pub(crate) pattern: SparsePattern,
    /// `map[k]`: where the model pattern's value `k` lies in `pattern`.
    pub(crate) map: Vec<usize>,
    /// The Hessian's values on the model's pattern, before the copy.
    pub(crate) model_values: Vec<f64>,
    /// The pair stencils it was built from.
    stencils: Vec<[usize; 4]>,
    /// The node couplings (`a < b`) they add.
    coupled: HashSet<(usize, usize)>,
    /// How many times the layout was built.
    pub builds: usize,
}

/// Whether a step of `model` solved in `mode` uses a grown layout.
pub(crate) fn applies(model: &Model, mode: LinearMode) -> bool {
    model.self_contact().is_some() && mode == LinearMode::Direct
}

/// The couplings of a four-node stencil, `a < b`.
fn couplings(s: &[usize; 4]) -> impl Iterator<Item = (usize, usize)> + '_ {
    (0..4).flat_map(move |i| (i + 1..4).map(move |j| (s[i].min(s[j]), s[i].max(s[j]))))
}

/// Makes `grown` hold the couplings a step from the first guess `y` needs
/// (module docs), rebinding `ws`'s linear solver and Hessian buffer to it
/// when it is rebuilt. Nothing without self-contact.
pub(crate) fn grow(
    model: &Model,
    grown: &mut Option<Grown>,
    ws: &mut NewtonWorkspace,
    y: &[f64],
) -> Result<(), LinearSolveError> {
    let Some(sc) = model.self_contact() else {
        return Ok(());
    };
    let trigger = TRIGGER * sc.distance();
    let have = grown.as_ref().map(|g| &g.coupled);
    let missing = |s: &[usize; 4]| have.is_none_or(|c| couplings(s).any(|p| !c.contains(&p)));
    if grown.is_some() && !sc.stencils_near(y, trigger).iter().any(missing) {
        return Ok(());
    }
    // Rebuilt from the pairs near now, with room: the layout follows the
    // contacts (folds and plies that part leave it at the next rebuild).
    let stencils = sc.stencils_near(y, ROOM * trigger);
    let builds = grown.as_ref().map_or(0, |g| g.builds);
    build(model, grown, ws, stencils, builds + 1)
}

/// Builds `grown` from `stencils` (a checkpoint's: the layout the run had
/// when it stopped) and rebinds `ws` to it: a resumed run factorises on
/// the same pattern as the uninterrupted one. Nothing for no stencils.
pub(crate) fn restore(
    model: &Model,
    grown: &mut Option<Grown>,
    ws: &mut NewtonWorkspace,
    stencils: &[[usize; 4]],
) -> Result<(), LinearSolveError> {
    if stencils.is_empty() || !applies(model, ws.linear.effective_mode()) {
        return Ok(());
    }
    build(model, grown, ws, stencils.to_vec(), 1)
}

/// The stencils `grown` was built from (none without a layout).
pub(crate) fn stencils(grown: &Option<Grown>) -> Vec<[usize; 4]> {
    grown.as_ref().map_or_else(Vec::new, |g| g.stencils.clone())
}

/// The layout of the model's pattern and `stencils`, `ws` rebound to it.
fn build(
    model: &Model,
    grown: &mut Option<Grown>,
    ws: &mut NewtonWorkspace,
    stencils: Vec<[usize; 4]>,
    builds: usize,
) -> Result<(), LinearSolveError> {
    let coupled: HashSet<(usize, usize)> = stencils.iter().flat_map(couplings).collect();
    let base = model.pattern();
    let mesh = model.mesh();
    let pattern = match model.bending() {
        Some(b) => SparsePattern::new(
            mesh.node_count(),
            (mesh.elements().chain(b.stencils())).chain(stencils.iter().map(|s| s.as_slice())),
        ),
        None => SparsePattern::new(
            mesh.node_count(),
            mesh.elements().chain(stencils.iter().map(|s| s.as_slice())),
        ),
    };
    let mut map = vec![0; base.nnz()];
    let (ptr, rows) = base.node_graph();
    for b in 0..mesh.node_count() {
        for p in ptr[b]..ptr[b + 1] {
            let a = rows[p];
            let q = pattern
                .node_block(a, b)
                .expect("the grown pattern holds the model's");
            for i in 0..3 {
                for j in 0..3 {
                    map[base.entry(p, b, i, j)] = pattern.entry(q, b, i, j);
                }
            }
        }
    }
    let (node_ptr, node_rows) = pattern.node_graph();
    let mut linear = LinearSolver::new(&pattern.col_ptr, &pattern.row_idx)?
        .with_transpose(pattern.transpose_map().to_vec())
        .with_node_blocks(node_ptr, node_rows)
        .with_mode(ws.linear.mode());
    if let Some(compact) = ws.linear.compact_pattern() {
        linear = linear.with_compact(compact.clone());
    }
    linear.stats = ws.linear.stats;
    ws.rebind(linear, pattern.nnz());
    *grown = Some(Grown {
        pattern,
        map,
        model_values: vec![0.0; base.nnz()],
        stencils,
        coupled,
        builds,
    });
    Ok(())
}
