//! The seeded random numbers of a drape test's specimens: SplitMix64
//! (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
//! OOPSLA 2014; the constants of Vigna's reference `splitmix64.c`).
//!
//! drape's own, a dozen lines, rather than a crate's: a specimen's
//! scenario records its seed, and the same seed must give the same
//! specimen in every later release, which a crate may change its
//! algorithm under.

/// SplitMix64: a 64-bit state advanced by the golden ratio's odd constant
/// and mixed by two xor-shift-multiplies.
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The generator started at `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`: the top 53 bits over 2^53.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal, by Box–Muller (the cosine branch; `1 − u` keeps
    /// the logarithm's argument in `(0, 1]`).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    /// The first outputs from seed 1234567 of Vigna's `splitmix64.c` (the
    /// reference implementation's published test vector).
    #[test]
    fn reference_outputs() {
        let mut g = SplitMix64::new(1234567);
        let expected = [
            6457827717110365317u64,
            3203168211198807973,
            9817491932198370423,
            4593380528125082431,
            16408922859458223821,
        ];
        for e in expected {
            assert_eq!(g.next_u64(), e);
        }
    }

    /// Uniforms in [0, 1) with mean 1/2 and normals with mean 0 and
    /// variance 1, to 4 standard errors of 10^5 draws.
    #[test]
    fn moments() {
        let n = 100_000;
        let mut g = SplitMix64::new(7);
        let u: Vec<f64> = (0..n).map(|_| g.uniform()).collect();
        assert!(u.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = u.iter().sum::<f64>() / n as f64;
        // sd of a uniform: 1/sqrt(12); of its mean over n: that / sqrt(n).
        assert!((mean - 0.5).abs() < 4.0 / (12.0 * n as f64).sqrt());
        let z: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let mean = z.iter().sum::<f64>() / n as f64;
        let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!(mean.abs() < 4.0 / (n as f64).sqrt());
        // The sample variance's sd is sqrt(2 / n) for a normal.
        assert!((var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt());
    }
}
