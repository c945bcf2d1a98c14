//! `[material] compression_ratio` (issue 31): the relaxed energy with a
//! fraction `r` of the elastic compressive stiffness. A sheet stretched
//! stores the elastic energy, a sheet compressed `r` times it, isotropic
//! and woven; `r = 0` is Pipkin's relaxed energy and `r = 1` the elastic
//! material; bad values and the wrong wrinkling model are refused at
//! their line.

mod common;

use common::{assert_error, build};
use std::path::Path;

/// A 10 cm x 5 cm sheet with `material` (whole lines) for its material.
fn scenario(material: &str) -> String {
    format!(
        "[mesh]
shape = \"rectangle\"
size = [0.1, 0.05]
divisions = [6, 3]
[material]
{material}
density = 320.0
thickness = 0.5e-3
[time]
segments = [{{ steps = 1, dt = 1.0e-3 }}]
"
    )
}

const ISOTROPIC: &str = "youngs_modulus = 2.0e6\npoisson_ratio = 0.3";
const WOVEN: &str = "model = \"orthotropic\"\nwarp_modulus = 5.0e6\nweft_modulus = 1.0e6\nshear_modulus = 5.0e4\npoisson_ratio = 0.3\nwarp_direction = [1.0, 1.0, 0.0]";

/// The membrane's strain energy (J) with every node's x scaled by `sx`.
fn energy_scaled(material: &str, sx: f64) -> f64 {
    let setup = build(&scenario(material), Path::new("test.toml")).unwrap();
    let mut y = setup.model.initial_positions().to_vec();
    for p in y.chunks_mut(3) {
        p[0] *= sx;
    }
    setup.model.strain_energy(&y)
}

/// Stretched along x (1 %, held straight across: taut where the lateral
/// strain is zero, `E22 = 0 > -nu E11`) the compression-soft sheet stores
/// the elastic energy; compressed by 1 % it stores `r` times it (slack:
/// `E11 < 0`, `E22 = 0`), for the isotropic and the woven material.
#[test]
fn tension_is_elastic_and_compression_is_the_ratio_of_it() {
    for law in [ISOTROPIC, WOVEN] {
        let none = format!("{law}\nwrinkling = \"none\"");
        let soft =
            |r: f64| format!("{law}\nwrinkling = \"relaxed-energy\"\ncompression_ratio = {r}");
        let r = 0.05;
        let taut = energy_scaled(&none, 1.01);
        let stretched = energy_scaled(&soft(r), 1.01);
        assert!(taut > 0.0);
        // The woven sheet's warp is at 45°: a uniaxial stretch along x is
        // partly shear there, which the relaxed energy keeps only where
        // both principal stresses pull; the isotropic sheet is taut.
        if law == ISOTROPIC {
            assert!(
                (stretched / taut - 1.0).abs() < 1e-12,
                "{stretched} vs {taut}"
            );
        }
        let elastic = energy_scaled(&none, 0.99);
        let compressed = energy_scaled(&soft(r), 0.99);
        let relaxed = energy_scaled(&format!("{law}\nwrinkling = \"relaxed-energy\""), 0.99);
        eprintln!(
            "compressed 1 %: elastic {elastic:.6e} J, r = {r}: {compressed:.6e} J, relaxed {relaxed:.6e} J"
        );
        let expected = r * elastic + (1.0 - r) * relaxed;
        assert!(
            (compressed / expected - 1.0).abs() < 1e-12,
            "{compressed} vs {expected}"
        );
        if law == ISOTROPIC {
            assert!(relaxed.abs() < 1e-20 * elastic, "{relaxed}");
        }
        assert_eq!(energy_scaled(&soft(0.0), 0.99), relaxed);
        let one = energy_scaled(&soft(1.0), 0.99);
        assert!((one / elastic - 1.0).abs() < 1e-12, "{one} vs {elastic}");
    }
}

/// A ratio outside [0, 1] or not a number, and a ratio with a wrinkling
/// model it does not apply to, are refused at the key's line with the
/// value.
#[test]
fn a_bad_compression_ratio_is_refused_at_its_line() {
    for (value, shown) in [
        ("1.5", "1.5"),
        ("-0.1", "-0.1"),
        ("nan", "NaN"),
        ("inf", "inf"),
    ] {
        let text = scenario(&format!(
            "{ISOTROPIC}\nwrinkling = \"relaxed-energy\"\ncompression_ratio = {value}"
        ));
        assert_error(
            &text,
            9,
            "material.compression_ratio",
            &["must lie in [0, 1]", &format!("not {shown}")],
        );
    }
    for model in ["none", "stress-projection"] {
        let text = scenario(&format!(
            "{ISOTROPIC}\nwrinkling = \"{model}\"\ncompression_ratio = 0.1"
        ));
        assert_error(
            &text,
            9,
            "material.compression_ratio",
            &[
                "relaxed-energy",
                &format!("not with wrinkling = \"{model}\""),
            ],
        );
    }
    let text = scenario(&format!("{ISOTROPIC}\ncompression_ratio = 0.1"));
    assert_error(
        &text,
        8,
        "material.compression_ratio",
        &["not with wrinkling = \"none\""],
    );
}
