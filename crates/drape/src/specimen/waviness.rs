//! A specimen's waviness: a smooth random field of a few low Fourier
//! modes over its plane (docs/theory.md, "The drape test's specimens").
//!
//! In the specimen's plane coordinates `(ξ, η)` about its centroid, with
//! `L` the largest distance of a node from it (a disc's radius),
//!
//! ```text
//! f(ξ, η) = Σ_(p,q) a_pq cos(π (p ξ + q η) / L + φ_pq)
//! w(ξ, η) = A f(ξ, η) / max_nodes |f|
//! ```
//!
//! over the wave numbers `(p, q)` with `0 < p² + q² ≤ K²` (`K` the
//! `waviness_modes`), one of each pair `±(p, q)`: `p > 0`, or `p = 0` and
//! `q > 0`. The mode `(p, q)` has the wavelength `2 L / √(p² + q²)`: the
//! specimen's diameter for the first ring of modes, down to `2 L / K`.
//! The amplitudes are `a_pq = z_pq / (p² + q²)` with `z_pq` standard
//! normal (a red spectrum: the longer waves dominate, as in a specimen's
//! lie after cutting), the phases `φ_pq` uniform in `[0, 2π)`, all drawn
//! from the seed in the modes' order (`p` then `q`, each ascending). The
//! field is scaled so that the largest offset of a node is exactly `A`.

use super::random::SplitMix64;

/// One Fourier mode: wave numbers, amplitude and phase.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Mode {
    p: f64,
    q: f64,
    amplitude: f64,
    phase: f64,
}

/// The field `f` of the seed and `K` (unscaled).
#[derive(Debug, Clone, PartialEq)]
pub struct Waviness {
    modes: Vec<Mode>,
    /// `L` (m).
    length: f64,
}

impl Waviness {
    /// The modes of `seed` up to wave number `modes` (`K`, ≥ 1) on a
    /// specimen of half-size `length` (`L`, m, > 0).
    pub fn new(seed: u64, modes: usize, length: f64) -> Self {
        let mut random = SplitMix64::new(seed);
        let k = modes as i64;
        let mut out = Vec::new();
        for p in 0..=k {
            for q in -k..=k {
                let r2 = p * p + q * q;
                if r2 == 0 || r2 > k * k || (p == 0 && q < 0) {
                    continue;
                }
                let amplitude = random.normal() / r2 as f64;
                let phase = std::f64::consts::TAU * random.uniform();
                out.push(Mode {
                    p: p as f64,
                    q: q as f64,
                    amplitude,
                    phase,
                });
            }
        }
        Self { modes: out, length }
    }

    /// `f(ξ, η)`.
    pub fn value(&self, [xi, eta]: [f64; 2]) -> f64 {
        let k = std::f64::consts::PI / self.length;
        self.modes
            .iter()
            .map(|m| m.amplitude * (k * (m.p * xi + m.q * eta) + m.phase).cos())
            .sum()
    }

    /// The number of modes.
    pub fn len(&self) -> usize {
        self.modes.len()
    }

    /// Whether there are none (never, for `K ≥ 1`).
    pub fn is_empty(&self) -> bool {
        self.modes.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::Waviness;

    /// The modes are half the nonzero lattice points in the disc of radius
    /// K (one of each pair ±(p, q)), counted by brute force.
    #[test]
    fn modes_are_half_the_lattice_disc() {
        for k in 1..=6usize {
            let ki = k as i64;
            let lattice = (-ki..=ki)
                .flat_map(|p| (-ki..=ki).map(move |q| p * p + q * q))
                .filter(|&r2| r2 > 0 && r2 <= ki * ki)
                .count();
            assert_eq!(Waviness::new(1, k, 1.0).len(), lattice / 2, "K = {k}");
        }
    }

    /// Periodic over 2L along ξ and η: every mode has a whole number of
    /// waves over 2L (to round-off of the phases' arguments).
    #[test]
    fn periodic_over_twice_the_length() {
        let w = Waviness::new(42, 3, 0.15);
        for &(x, y) in &[(0.01, 0.02), (-0.1, 0.07), (0.13, -0.12)] {
            let a = w.value([x, y]);
            let b = w.value([x + 0.3, y]);
            let c = w.value([x, y + 0.3]);
            assert!((a - b).abs() < 1e-12 && (a - c).abs() < 1e-12);
        }
    }

    /// Same seed, same field; another seed, another.
    #[test]
    fn seeded() {
        let p = [0.03, -0.05];
        assert_eq!(
            Waviness::new(9, 3, 0.15).value(p),
            Waviness::new(9, 3, 0.15).value(p)
        );
        assert_ne!(
            Waviness::new(9, 3, 0.15).value(p),
            Waviness::new(10, 3, 0.15).value(p)
        );
    }
}
