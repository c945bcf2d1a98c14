//! External loads (docs/theory.md §1.5): dead surface loads, gravity, follower
//! pressure and nodal forces, each with an optional linear ramp.

pub mod cavity;
pub mod gas;
pub mod pressure;

/// What a load is.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadKind {
    /// Force per unit initial area `q` (N/m^2) in a fixed direction;
    /// consistent nodal forces `f^a = q integral phi^a dA0`.
    Surface {
        /// `q` (N/m^2).
        force: [f64; 3],
    },
    /// Weight: a surface load `q = rho t g`.
    Gravity {
        /// `g` (m/s^2).
        acceleration: [f64; 3],
    },
    /// Follower pressure `p` (Pa) along the current normal `g_1 x g_2`, per
    /// current area.
    Pressure {
        /// `p` (Pa).
        value: f64,
    },
    /// The same force on each of the listed nodes.
    Nodal {
        /// Node indices.
        nodes: Vec<usize>,
        /// Force per node (N).
        force: [f64; 3],
    },
}

/// A load and its time function.
#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    /// What it is.
    pub kind: LoadKind,
    /// Rise time (s): the load grows linearly from 0 at `t = 0` to full at
    /// `t = ramp`, then stays. `None`: full from the start.
    pub ramp: Option<f64>,
}

impl Load {
    /// Load factor at time `t` (dynamic analysis): `min(t / ramp, 1)`.
    pub fn factor(&self, t: f64) -> f64 {
        match self.ramp {
            Some(r) if r > 0.0 => (t / r).clamp(0.0, 1.0),
            _ => 1.0,
        }
    }
}
