//! Penalty enforcement: the potential `C = 1/2 eta g^2` for every node–body
//! pair with `g < 0`, so that
//!
//! ```text
//! f_p = dC/dy_p = eta g n            (added to the residual G)
//! H_pp += eta (n n^T + g dn/dy)      (added to the Hessian)
//! ```
//!
//! with `n = dg/dy` and `dn/dy = d^2 g/dy^2` from the obstacle. The contact
//! force on the node, `-eta g n`, pushes it out along `n`. At rest on a
//! surface a node carrying a force `F` penetrates by `F / eta`.

use super::{ContactModel, ContactState};
use crate::solver::SparsePattern;

/// Where [`ContactModel::add_penalty`] adds its Hessian: the values on
/// the model's pattern, and which nodes' pair Hessians it projects to
/// their positive semi-definite part (`None`: none).
#[derive(Debug)]
pub struct PenaltyHessian<'a> {
    /// The Hessian's values on `pattern`.
    pub values: &'a mut [f64],
    /// The model's sparse pattern.
    pub pattern: &'a SparsePattern,
    /// One flag per node: whose pair Hessians are projected.
    pub project: Option<&'a [bool]>,
}

impl ContactModel {
    /// Adds the penalty terms at positions `y`, time `t`, to `g` and (if
    /// given) to the Hessian values `h` on `pattern`; returns the penalty
    /// energy (J). With node flags in `h`'s third part, the 3x3 Hessian of
    /// a pair whose node is flagged there is replaced by its positive semi-definite part
    /// ([`crate::psd`]): `eta (n n^T + g dn/dy)` is indefinite where the
    /// node penetrates a convex surface (`g < 0`, `dn/dy` positive on the
    /// tangent plane).
    pub fn add_penalty(
        &self,
        stiffness: f64,
        y: &[f64],
        t: f64,
        state: &ContactState,
        g: &mut [f64],
        h: Option<PenaltyHessian>,
    ) -> f64 {
        let (pairs, _) = self.near_pairs(y, t, state, 0.0, false);
        let mut energy = 0.0;
        let mut h = h;
        for (p, _, prox) in pairs {
            let (gap, n, dn) = (prox.gap, prox.normal, prox.normal_derivative);
            energy += 0.5 * stiffness * gap * gap;
            for i in 0..3 {
                g[3 * p + i] += stiffness * gap * n[i];
            }
            if let Some(PenaltyHessian {
                values: h,
                pattern,
                project,
            }) = h.as_mut()
            {
                let block = pattern
                    .node_block(p, p)
                    .expect("diagonal blocks are in the pattern");
                let mut k: [f64; 9] = std::array::from_fn(|ij| {
                    stiffness * (n[ij / 3] * n[ij % 3] + gap * dn[ij / 3][ij % 3])
                });
                if project.is_some_and(|flags| flags[p]) {
                    crate::psd::project(&mut k, 3, 3);
                }
                for i in 0..3 {
                    for j in 0..3 {
                        h[pattern.entry(block, p, i, j)] += k[3 * i + j];
                    }
                }
            }
        }
        energy
    }
}
