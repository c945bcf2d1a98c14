//! Numbers in messages as a person writes them: plain between 1e-4 and
//! 1e6 (`0.15`, `1200`), in e-notation outside (`1e308`, `2.5e-35`), each
//! with the fewest digits that read back as the number. Rust's `{}`
//! writes every digit of the plain form: `1e308` with 309 digits, a
//! centroid of `2.5e-35` with 36 decimals.

/// `x` as a person writes it (see the module).
pub fn human(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A point or vector `[x, y, z]`, each coordinate by [`human`].
pub fn human_point(p: [f64; 3]) -> String {
    format!("[{}, {}, {}]", human(p[0]), human(p[1]), human(p[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_in_the_middle_and_exponents_outside() {
        assert_eq!(human(0.15), "0.15");
        assert_eq!(human(1200.0), "1200");
        assert_eq!(human(0.0), "0");
        assert_eq!(human(-0.5), "-0.5");
        assert_eq!(human(1e-4), "0.0001");
        assert_eq!(human(1e308), "1e308");
        assert_eq!(human(2.5e-35), "2.5e-35");
        assert_eq!(human(1e6), "1e6");
        assert_eq!(human(f64::INFINITY), "inf");
        // The shortest digits that read back as the number.
        assert_eq!(human(0.1 + 0.2), "0.30000000000000004");
        assert_eq!(human_point([2.5e-35, 0.0, -0.05]), "[2.5e-35, 0, -0.05]");
    }
}
