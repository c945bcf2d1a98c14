//! `[test]` and `[specimen]`: how the specimens of a drape test differ
//! (README, "The drape test"), the specimens' scenarios a test runs, and
//! the perturbation a specimen's run applies ([`crate::specimen`]).

use super::check::Checker;
use super::material::has_axis;
use super::{MaterialSpec, Scenario, ScenarioError};
use crate::contact::ContactModel;
use crate::mesh::Mesh;
use crate::specimen::random::SplitMix64;
use crate::specimen::{Face, Perturbation, SpecimenPlane, perturb_mesh};
use serde::Deserialize;
use std::path::Path;

/// The largest `waviness_modes`: beyond 8 rings of modes the waves are
/// shorter than a specimen's folds, no longer a lie of the whole sheet.
pub const MAX_WAVINESS_MODES: usize = 8;

/// The largest waviness, as a fraction of the mesh's size
/// ([`Mesh::diagonal`]): a specimen is a sheet that lies almost flat.
pub const MAX_WAVINESS_FRACTION: f64 = 0.1;

/// `[test]`: how `drape test` makes its specimens differ. `drape run`
/// ignores it (its values are still checked).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestSpec {
    /// The waviness' amplitude `A` (m): each specimen's largest offset
    /// from its plane, a field of its own seed. >= 0, at most a tenth of
    /// the mesh's size. Default 5e-4 (half a millimetre).
    #[serde(default = "default_test_waviness")]
    pub waviness: f64,
    /// The waviness' largest wave number `K` (1 to 8): wavelengths from the
    /// specimen's diameter down to its diameter / K. Default 3.
    #[serde(default = "default_modes")]
    pub waviness_modes: usize,
    /// The cuts' angles to the warp (degrees): each specimen's drawn
    /// uniformly in `[-cut_angle, cut_angle]`, in [0, 90]. Default 2.
    #[serde(default = "default_cut_angle")]
    pub cut_angle: f64,
    /// `"both"` (default: specimens 0, 2, 4, ... face up, 1, 3, 5, ... face
    /// down, as ISO 9073-9 tests both faces) or `"up"` (every one face up).
    #[serde(default)]
    pub faces: Faces,
}

impl Default for TestSpec {
    fn default() -> Self {
        Self {
            waviness: default_test_waviness(),
            waviness_modes: default_modes(),
            cut_angle: default_cut_angle(),
            faces: Faces::default(),
        }
    }
}

fn default_test_waviness() -> f64 {
    5e-4
}
fn default_modes() -> usize {
    3
}
fn default_cut_angle() -> f64 {
    2.0
}

/// The values of `[test] faces`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Faces {
    /// Alternately face up and face down.
    #[default]
    Both,
    /// Every specimen face up.
    Up,
}

/// `[specimen]`: this scenario is one specimen of a drape test, perturbed
/// as its keys say (`drape test` writes them; zero waviness and angle face
/// up is the plain scenario, bit for bit).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecimenSpec {
    /// The waviness field's seed, an integer in [0, 2^63). Default 0.
    #[serde(default)]
    pub seed: u64,
    /// The waviness' amplitude `A` (m), >= 0, at most a tenth of the
    /// mesh's size. Default 0.
    #[serde(default)]
    pub waviness: f64,
    /// The waviness' largest wave number `K`, 1 to 8. Default 3.
    #[serde(default = "default_modes")]
    pub waviness_modes: usize,
    /// The cut's angle to the warp `θ` (degrees), in [-90, 90]: the warp
    /// direction turned by it about the plane's normal. Default 0.
    #[serde(default)]
    pub cut_angle: f64,
    /// `"up"` (default) or `"down"` (turned over about the plane's first
    /// axis).
    #[serde(default)]
    pub face: Face,
}

/// One specimen of a drape test: its number, its perturbation and its
/// scenario's text.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecimenPlan {
    /// 0, 1, 2, ...
    pub index: usize,
    /// The `[specimen]` table of its scenario.
    pub spec: SpecimenSpec,
    /// Its scenario: the test's, without `[test]`, with `[specimen]` and its
    /// file paths absolute.
    pub text: String,
}

impl SpecimenPlan {
    /// The directory name under `DIR/specimens`: `0000`, `0001`, ...
    pub fn name(&self) -> String {
        format!("{:04}", self.index)
    }
}

impl Scenario {
    /// The `count` specimens of a drape test of this scenario (read from
    /// `file`, whose text is `source`) with the test's `seed`.
    ///
    /// Specimen `i`'s randomness comes from the `i`-th output of a
    /// SplitMix64 stream started at `seed`, so a specimen does not depend
    /// on how many there are: its cut angle is `cut_angle (2u − 1)` (`u`
    /// its generator's first uniform), its waviness seed its next 63 bits.
    ///
    /// # Errors
    /// A scenario that is already a specimen, out-of-range `[test]` values,
    /// a text that cannot be rewritten.
    pub fn specimens(
        &self,
        file: &Path,
        source: &str,
        count: usize,
        seed: u64,
    ) -> Result<Vec<SpecimenPlan>, ScenarioError> {
        let c = Checker { file, source };
        if self.specimen.is_some() {
            return Err(c.invalid(
                "",
                None,
                "specimen",
                "makes this scenario one specimen of a drape test already: run the test on the scenario it was made from (a [test] table says how its specimens differ)".into(),
            ));
        }
        let test = self.test.clone().unwrap_or_default();
        check_test(&c, &test, None)?;
        let mut table: toml::Table = toml::from_str(source).map_err(|e| ScenarioError::Parse {
            file: file.to_path_buf(),
            line: None,
            message: e.message().to_string(),
        })?;
        table.remove("test");
        let folder = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let folder = std::path::absolute(&folder).unwrap_or(folder);
        super::absolute_paths(&mut table, &folder);
        let mut stream = SplitMix64::new(seed);
        let mut plans = Vec::with_capacity(count);
        for index in 0..count {
            let mut own = SplitMix64::new(stream.next_u64());
            let cut_angle = test.cut_angle * (2.0 * own.uniform() - 1.0);
            let spec = SpecimenSpec {
                seed: own.next_u64() >> 1,
                waviness: test.waviness,
                waviness_modes: test.waviness_modes,
                cut_angle,
                face: match test.faces {
                    Faces::Both if index % 2 == 1 => Face::Down,
                    _ => Face::Up,
                },
            };
            table.insert("specimen".into(), toml::Value::Table(spec_table(&spec)));
            let text = toml::to_string(&table).map_err(|e| ScenarioError::Parse {
                file: file.to_path_buf(),
                line: None,
                message: format!("cannot write specimen {index}'s scenario: {e}"),
            })?;
            plans.push(SpecimenPlan { index, spec, text });
        }
        Ok(plans)
    }
}

/// `[specimen]` as a TOML table.
fn spec_table(s: &SpecimenSpec) -> toml::Table {
    let mut t = toml::Table::new();
    // Below 2^63 by construction (the plan's seeds are 63 bits).
    t.insert("seed".into(), toml::Value::Integer(s.seed as i64));
    t.insert("waviness".into(), toml::Value::Float(s.waviness));
    t.insert(
        "waviness_modes".into(),
        toml::Value::Integer(s.waviness_modes as i64),
    );
    t.insert("cut_angle".into(), toml::Value::Float(s.cut_angle));
    t.insert("face".into(), toml::Value::String(s.face.name().into()));
    t
}

/// The waviness' range: >= 0 and finite, at most [`MAX_WAVINESS_FRACTION`]
/// of `mesh`'s size (when there is one to compare with).
fn check_waviness(
    c: &Checker,
    table: &str,
    waviness: f64,
    modes: usize,
    mesh: Option<&Mesh>,
) -> Result<(), ScenarioError> {
    if !(waviness.is_finite() && waviness >= 0.0) {
        return Err(c.invalid(
            table,
            None,
            "waviness",
            format!("must be a finite amplitude >= 0 (m), not {waviness}"),
        ));
    }
    if let Some(mesh) = mesh {
        let most = MAX_WAVINESS_FRACTION * mesh.diagonal();
        if waviness > most {
            return Err(c.invalid(
                table,
                None,
                "waviness",
                format!(
                    "= {waviness} m is more than a tenth of the mesh's size ({most} m): a specimen lies almost flat; is it in m?"
                ),
            ));
        }
    }
    if !(1..=MAX_WAVINESS_MODES).contains(&modes) {
        return Err(c.invalid(
            table,
            None,
            "waviness_modes",
            format!("must lie in 1 to {MAX_WAVINESS_MODES}, not {modes}"),
        ));
    }
    Ok(())
}

/// `[test]`'s ranges.
fn check_test(c: &Checker, t: &TestSpec, mesh: Option<&Mesh>) -> Result<(), ScenarioError> {
    check_waviness(c, "test", t.waviness, t.waviness_modes, mesh)?;
    if !(t.cut_angle.is_finite() && (0.0..=90.0).contains(&t.cut_angle)) {
        return Err(c.invalid(
            "test",
            None,
            "cut_angle",
            format!("must lie in [0, 90] (degrees), not {}", t.cut_angle),
        ));
    }
    Ok(())
}

/// The scenario's `[test]` checked, and its `[specimen]`: the
/// perturbation on the plane of `mesh`, with the material's warp
/// direction cut and turned over (`None` where the material has no warp,
/// or there is nothing to perturb).
pub(super) fn specimen_of(
    c: &Checker,
    scenario: &Scenario,
    mesh: &Mesh,
) -> Result<Option<(Perturbation, SpecimenPlane, Option<MaterialSpec>)>, ScenarioError> {
    if let Some(t) = &scenario.test {
        check_test(c, t, Some(mesh))?;
    }
    let Some(s) = &scenario.specimen else {
        return Ok(None);
    };
    check_waviness(c, "specimen", s.waviness, s.waviness_modes, Some(mesh))?;
    if !(s.cut_angle.is_finite() && (-90.0..=90.0).contains(&s.cut_angle)) {
        return Err(c.invalid(
            "specimen",
            None,
            "cut_angle",
            format!("must lie in [-90, 90] (degrees), not {}", s.cut_angle),
        ));
    }
    if s.seed > i64::MAX as u64 {
        return Err(c.invalid(
            "specimen",
            None,
            "seed",
            format!("must lie in [0, 2^63), not {}", s.seed),
        ));
    }
    let p = Perturbation {
        seed: s.seed,
        waviness: s.waviness,
        modes: s.waviness_modes,
        cut_angle: s.cut_angle,
        face: s.face,
    };
    if p.is_identity() {
        return Ok(None);
    }
    let plane = SpecimenPlane::of(mesh)
        .map_err(|e| c.invalid("specimen", None, "waviness", e.to_string()))?;
    let m = &scenario.material;
    let turned = has_axis(m).then(|| {
        let mut turned = m.clone();
        turned.warp_direction = Some(plane.turn(m.warp_direction.unwrap_or([1.0, 0.0, 0.0]), &p));
        turned
    });
    Ok(Some((p, plane, turned)))
}

/// `mesh` made wavy by `p`, held flat where a node starts within the
/// waviness' amplitude of an obstacle of `contact` (the drape tester's
/// grip), so that no node starts inside one.
pub(super) fn make_wavy(
    mesh: &mut Mesh,
    p: &Perturbation,
    plane: &SpecimenPlane,
    contact: Option<&ContactModel>,
) {
    let held: Vec<bool> = (mesh.nodes.iter())
        .map(|&x| {
            contact.is_some_and(|c| {
                (c.bodies.iter()).any(|b| b.proximity(x, 0.0, None).gap <= p.waviness)
            })
        })
        .collect();
    perturb_mesh(mesh, plane, p, &held);
}
