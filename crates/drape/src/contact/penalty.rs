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

impl ContactModel {
    /// Adds the penalty terms at positions `y`, time `t`, to `g` and (if
    /// given) to the Hessian values `h` on `pattern`; returns the penalty
    /// energy (J).
    pub fn add_penalty(
        &self,
        stiffness: f64,
        y: &[f64],
        t: f64,
        state: &ContactState,
        g: &mut [f64],
        h: Option<(&mut [f64], &SparsePattern)>,
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
            if let Some((h, pattern)) = h.as_mut() {
                let block = pattern
                    .node_block(p, p)
                    .expect("diagonal blocks are in the pattern");
                for i in 0..3 {
                    for j in 0..3 {
                        h[pattern.entry(block, p, i, j)] +=
                            stiffness * (n[i] * n[j] + gap * dn[i][j]);
                    }
                }
            }
        }
        energy
    }
}
