//! Issue 43: the multilevel settle (`[refine]`). A uniformly refined
//! smooth problem lands where the run started on the fine mesh does; a
//! refinement conserves mass, area and weight and leaves a state at rest
//! unstrained; an interrupted multilevel run resumes across a refinement
//! to the same history, byte for byte; bad `[refine]` keys are refused
//! by name.

mod common;

use common::{assert_error, column, read_history, setup, temp_dir};
use drape::levels::{self, Transfer};
use drape::progress::StepProgress;
use drape::scenario::Scenario;
use drape::simulation::{self, RunControl, RunError};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A clamped square membrane (0.3 m, `n` x `n` squares of T3) under 20
/// Pa, run dynamically to rest; `refine`: a `[refine]` table to add. A
/// uniform refinement of the `n` grid is the `2n` grid, node for node.
fn inflated(n: usize, refine: &str) -> String {
    format!(
        r#"
[mesh]
shape = "rectangle"
size = [0.3, 0.3]
divisions = [{n}, {n}]
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "pressure"
value = 20.0
ramp = 0.1
[[fix]]
boundary = true
[time]
segments = [{{ steps = 30, dt = 2.0e-2 }}]
[output]
every = 1000
[[monitor]]
name = "center"
at = [0.0, 0.0, 0.0]
{refine}
"#
    )
}

/// Runs scenario `text` through the multilevel driver into `out`.
fn run_levels(
    text: &str,
    out: &Path,
    control: RunControl,
    observer: &mut dyn FnMut(&simulation::StepInfo),
) -> Result<simulation::Summary, RunError> {
    let path = Path::new("test.toml");
    let scenario = Scenario::parse(text, path).unwrap();
    let s = scenario.build(path, text).unwrap();
    levels::run_with(&scenario, (path, text), &s, out, observer, control)
}

/// The square of `n` x `n` squares (of order `order`) refined once
/// everywhere lands on the centre deflection of the run started on the
/// twice finer grid, to well within the coarse grid's own error; returns
/// the refined run's summary.
fn refined_lands_on_fine(n: usize, order: usize) -> simulation::Summary {
    let square = |n: usize, refine: &str| {
        inflated(n, refine).replace("[mesh]", &format!("[mesh]\norder = {order}"))
    };
    let deflection = |text: &str| {
        let dir = temp_dir("inflated");
        let summary = run_levels(text, &dir, RunControl::default(), &mut |_| {}).unwrap();
        (summary.monitors["center"][2], summary)
    };
    let (coarse, _) = deflection(&square(n, ""));
    let (fine, _) = deflection(&square(2 * n, ""));
    let (refined, summary) = deflection(&square(n, "[refine]\nlevels = 1\nwhere = \"all\""));
    assert_eq!(summary.levels.len(), 2, "{:?}", summary.levels);
    assert_eq!(summary.levels[1].elements, 4 * summary.levels[0].elements);
    assert_eq!(summary.elements, summary.levels[1].elements);
    let error = (refined - fine).abs();
    assert!(
        error < 0.1 * (coarse - fine).abs(),
        "coarse {coarse}, refined {refined}, fine {fine}"
    );
    summary
}

/// A coarse T3 square refined once everywhere and settled statically
/// lands on the run started on the twice finer grid.
#[test]
fn a_uniformly_refined_run_matches_the_run_started_fine() {
    let summary = refined_lands_on_fine(6, 1);
    // No pedestal: no drape coefficient, said so.
    assert!(summary.levels[0].drape_coefficient.is_none());
    assert!(
        summary.levels[0]
            .note
            .as_deref()
            .unwrap()
            .contains("no drape coefficient")
    );
}

/// The same for quadratic triangles (T6), each split into four T6 by its
/// own interpolation (measured: the refined run equals the finer grid's
/// to 4e-13 m, the coarse grid 0.11 mm off).
#[test]
fn a_uniformly_refined_t6_run_matches_the_run_started_fine() {
    refined_lands_on_fine(3, 2);
}

/// The refined model has the coarse one's mass, area and weight to
/// round-off (the children tile their parent on the flat reference), and
/// a state that is its reference — flat, or a rigid motion of it — carried
/// over is unstrained: no energy appears.
#[test]
fn a_refinement_conserves_mass_and_weight_and_leaves_rest_at_rest() {
    let text = common::fabric(
        "[[load]]\nkind = \"gravity\"\nacceleration = [0.0, 0.0, -9.81]\n\
         [time]\nsegments = [{ steps = 1, dt = 1.0e-3 }]\n",
    );
    let path = Path::new("test.toml");
    let scenario = Scenario::parse(&text, path).unwrap();
    let coarse = scenario.build(path, &text).unwrap();
    let mesh = coarse.model.mesh();
    let marked: Vec<bool> = (0..mesh.element_count()).map(|e| e % 7 < 2).collect();
    let transfer = Transfer::new(mesh, &marked, &[]).unwrap();
    let fine = scenario
        .build_level(path, &text, transfer.refinement.mesh.clone(), Vec::new())
        .unwrap();
    assert!(fine.model.mesh().element_count() > mesh.element_count());
    let area = |m: &drape::mesh::Mesh| {
        m.elements()
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|v| m.nodes[v]);
                let (u, v) = (
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                    [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                );
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
            })
            .sum::<f64>()
    };
    let pairs = [
        ("mass", coarse.model.total_mass(), fine.model.total_mass()),
        ("area", area(coarse.model.mesh()), area(fine.model.mesh())),
    ];
    for (name, a, b) in pairs {
        assert!((a - b).abs() <= 1e-13 * a, "{name}: {a} against {b}");
    }
    let weight = |s: &drape::setup::Setup| {
        let mut f = vec![0.0; s.model.dofs()];
        s.model.dead_forces(1.0, Some(1.0), &mut f);
        f.chunks(3)
            .fold([0.0; 3], |w, p| [w[0] + p[0], w[1] + p[1], w[2] + p[2]])
    };
    let (a, b) = (weight(&coarse), weight(&fine));
    assert!(
        (a[2] - b[2]).abs() <= 1e-13 * a[2].abs(),
        "{a:?} against {b:?}"
    );
    // The reference moved rigidly, carried over: no strain.
    let (c, s) = (0.8f64, 0.6f64);
    let moved: Vec<f64> = coarse
        .model
        .initial_positions()
        .chunks(3)
        .flat_map(|p| [c * p[0] - s * p[2], p[1] + 0.1, s * p[0] + c * p[2] - 0.3])
        .collect();
    let carried = transfer.carry(&moved);
    let strain = fine.model.strain_energy(&carried);
    assert!(strain.abs() < 1e-18, "strain energy {strain} J");
}

/// The multilevel drape tester (`tests/scenarios/multilevel-tester.toml`:
/// an 8-ring disc on a pedestal, its weight put on in 6 static
/// increments, refined twice along its folds, checkpointing every step).
fn tester() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenarios/multilevel-tester.toml"),
    )
    .unwrap()
}

/// The multilevel run of `text` into `out`, stopped (as by Ctrl-C) after
/// step `step`, `check` seeing the directory, then resumed to its end.
fn stopped_and_resumed(
    text: &str,
    out: &Path,
    step: usize,
    check: impl FnOnce(&Path),
) -> simulation::Summary {
    let stop = AtomicBool::new(false);
    let control = RunControl {
        stop: Some(&stop),
        ..RunControl::default()
    };
    let e = run_levels(text, out, control, &mut |info| {
        if info.step == step {
            stop.store(true, Ordering::SeqCst);
        }
    })
    .unwrap_err();
    assert!(matches!(e, RunError::Interrupted { .. }), "{e}");
    check(out);
    let control = RunControl {
        resume: true,
        ..RunControl::default()
    };
    run_levels(text, out, control, &mut |_| {}).unwrap()
}

/// The levels in the summary with a drape coefficient each, the history's
/// `elements` rising level by level and its time rising; interrupted on
/// the first refined level's step and resumed, the run ends with the
/// uninterrupted run's history byte for byte.
#[test]
fn a_multilevel_settle_resumes_across_a_refinement_bit_for_bit() {
    let text = tester();
    let whole = temp_dir("levels-whole");
    let summary = run_levels(&text, &whole, RunControl::default(), &mut |_| {}).unwrap();
    assert_eq!(summary.levels.len(), 3, "{:?}", summary.levels);
    for l in &summary.levels {
        assert!(
            l.drape_coefficient.is_some_and(|dc| dc > 0.0 && dc < 1.0),
            "{l:?}"
        );
        assert!(l.folds.is_some(), "{l:?}");
    }
    assert!(
        summary
            .levels
            .windows(2)
            .all(|w| w[1].elements > w[0].elements)
    );
    let (header, rows) = read_history(&whole);
    let elements = column(&header, &rows, "elements");
    let time = column(&header, &rows, "time");
    assert!(elements.windows(2).all(|w| w[1] >= w[0]), "{elements:?}");
    assert!(time.windows(2).all(|w| w[1] > w[0]), "{time:?}");
    assert_eq!(*elements.last().unwrap(), summary.levels[2].elements as f64);
    // The initial row, the six increments, then each level's own (one,
    // or more where its increment was cut back).
    for l in &summary.levels[1..] {
        let at = elements.iter().filter(|&&e| e == l.elements as f64).count();
        assert_eq!(at, l.steps, "{l:?}");
    }
    assert_eq!(rows.len(), 1 + summary.steps);

    // Stop after the first refined level's increment (step 7).
    let cut = temp_dir("levels-cut");
    let resumed = stopped_and_resumed(&text, &cut, 7, |_| {});
    assert_eq!(
        std::fs::read(whole.join("history.csv")).unwrap(),
        std::fs::read(cut.join("history.csv")).unwrap()
    );
    let dcs = |s: &simulation::Summary| {
        s.levels
            .iter()
            .map(|l| (l.elements, l.drape_coefficient, l.folds, l.steps))
            .collect::<Vec<_>>()
    };
    assert_eq!(dcs(&summary), dcs(&resumed));
    // Every level's final shape is in the collection, the resumed run's
    // as the whole run's.
    let pvd = |dir: &Path| std::fs::read_to_string(dir.join("fields.pvd")).unwrap();
    let mut end = 0;
    for l in &summary.levels {
        end += l.steps;
        let frame = format!("fields/step_{end:06}.vtu");
        assert!(
            pvd(&whole).contains(&frame),
            "{frame} not in\n{}",
            pvd(&whole)
        );
    }
    assert_eq!(pvd(&whole), pvd(&cut));
}

/// A multilevel settle killed on its second refined level (here: a panic
/// after that level's step, before the run could record it) leaves no
/// summary that says `"completed"` — a finished coarser level writes
/// none, so the run does not look finished — and a checkpoint of the
/// level's start, written without `checkpoint_every` (0 here), from
/// which it resumes to the uninterrupted run's history and collection,
/// byte for byte.
#[test]
fn a_multilevel_settle_killed_on_a_finer_level_resumes_from_that_level() {
    let text = tester().replace("checkpoint_every = 1", "checkpoint_every = 0");
    assert!(text.contains("checkpoint_every = 0"));
    let whole = temp_dir("levels-kill-whole");
    let summary = run_levels(&text, &whole, RunControl::default(), &mut |_| {}).unwrap();
    let last = summary.steps;
    assert_eq!(summary.levels.len(), 3, "{:?}", summary.levels);
    let killed = temp_dir("levels-killed");
    let kill = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_levels(&text, &killed, RunControl::default(), &mut |info| {
            assert!(info.step < last, "killed");
        })
    }));
    assert!(kill.is_err(), "the run was not killed");
    assert!(
        !killed.join("summary.json").exists(),
        "{}",
        std::fs::read_to_string(killed.join("summary.json")).unwrap()
    );
    assert!(killed.join("checkpoint.bin").exists());
    let control = RunControl {
        resume: true,
        ..RunControl::default()
    };
    let resumed = run_levels(&text, &killed, control, &mut |_| {}).unwrap();
    assert_eq!(resumed.steps, last);
    for file in ["history.csv", "fields.pvd"] {
        assert_eq!(
            std::fs::read(whole.join(file)).unwrap(),
            std::fs::read(killed.join(file)).unwrap(),
            "{file}"
        );
    }
    assert_eq!(resumed.levels.len(), 3);
}

/// With a stick hysteresis (its plastic curvatures in the state, carried
/// onto each finer level with the springs loaded) a multilevel settle
/// stopped on its first refined level resumes from that level's
/// checkpoint — its plastic curvatures those of the finer mesh's patches
/// — to the uninterrupted run's history byte for byte, and slips on the
/// way.
#[test]
fn a_multilevel_settle_with_a_stick_resumes_on_a_finer_level() {
    let text = tester().replace(
        "bending_rigidity = 2.0e-5\n",
        "bending_rigidity = 2.0e-5\nbending_hysteresis = 1.0e-4\nbending_hysteresis_stiffness = 1.0e-4\n",
    );
    assert!(text.contains("bending_hysteresis_stiffness"));
    let whole = temp_dir("levels-stick-whole");
    let summary = run_levels(&text, &whole, RunControl::default(), &mut |_| {}).unwrap();
    assert_eq!(summary.levels.len(), 3, "{:?}", summary.levels);
    let cut = temp_dir("levels-stick-cut");
    let resumed = stopped_and_resumed(&text, &cut, 7, |cut| {
        let bytes = std::fs::read(cut.join("checkpoint.bin")).unwrap();
        let levels = simulation::Checkpoint::recorded_levels(&bytes).unwrap();
        assert_eq!(
            levels.records.len(),
            1,
            "stopped on the first refined level"
        );
    });
    assert_eq!(
        std::fs::read(whole.join("history.csv")).unwrap(),
        std::fs::read(cut.join("history.csv")).unwrap()
    );
    assert_eq!(resumed.levels.len(), 3);
    let (header, rows) = read_history(&whole);
    let dissipated = column(&header, &rows, "friction_dissipation");
    assert!(*dissipated.last().unwrap() > 0.0, "{dissipated:?}");
}

/// `also`: with a Dörfler share that marks almost nothing, `"rim"` still
/// splits every edge of the 8-ring disc's rim (48 new nodes at least),
/// and `"contact"` the triangles across the pedestal's edge.
#[test]
fn the_rim_and_the_contact_line_are_refined_when_asked() {
    let added = |also: &str| {
        let text = tester().replace(
            "levels = 2\ntolerance = 0.0",
            &format!("levels = 1\ntolerance = 0.0\nfraction = 0.001\nalso = [{also}]"),
        );
        let dir = temp_dir("levels-also");
        let summary = run_levels(&text, &dir, RunControl::default(), &mut |_| {}).unwrap();
        summary.levels[1].nodes - summary.levels[0].nodes
    };
    let (none, rim, contact) = (added(""), added("\"rim\""), added("\"contact\""));
    assert!(none < 48, "{none}");
    assert!(rim >= 48 + none, "{rim} against {none}");
    // The pedestal's edge (r = 9 cm) crosses rings 4 and 5 of 8: at
    // least 24 edges of the triangles across it are split.
    assert!(contact >= 24 + none, "{contact} against {none}");
}

/// `[refine] resolution`: the tolerance ends the refinement only on a
/// mesh that resolves the fabric's gravity bending length. The tester's
/// fabric: `l = (B / w)^(1/3)` with `B` = 2e-5 N m and `w` = 1.8816 N/m²
/// (its surface load), 22.0 mm. Refined everywhere with a tolerance any
/// change meets, the run stops after its first refinement; asked for a
/// mean edge between the second refinement's and the first's, it goes
/// on to the second and stops there; asked for one finer than the last
/// mesh it may make, it says it did not converge.
#[test]
fn the_tolerance_waits_for_a_mesh_that_resolves_the_bending_length() {
    let uniform = |resolution: Option<f64>| {
        let extra = resolution.map_or(String::new(), |r| format!("\nresolution = {r}"));
        tester().replace(
            "levels = 2\ntolerance = 0.0",
            &format!("levels = 2\ntolerance = 1.0\nwhere = \"all\"{extra}"),
        )
    };
    let text = uniform(None);
    let path = Path::new("test.toml");
    let built = Scenario::parse(&text, path)
        .unwrap()
        .build(path, &text)
        .unwrap();
    let l = built.model.bending_length().unwrap();
    let closed = (2.0e-5f64 / 1.8816).cbrt();
    assert!((l - closed).abs() < 1e-12 * closed, "{l} against {closed}");
    // The mean edges of the meshes a uniform refinement makes.
    let mut meshes = vec![built.model.mesh().clone()];
    for _ in 0..2 {
        let last = meshes.last().unwrap();
        let all = vec![true; last.element_count()];
        meshes.push(Transfer::new(last, &all, &[]).unwrap().refinement.mesh);
    }
    let h: Vec<f64> = meshes.iter().map(levels::mean_edge).collect();
    assert!(h[0] > h[1] && h[1] > h[2], "{h:?}");
    let run = |text: &str| {
        let dir = temp_dir("levels-resolution");
        run_levels(text, &dir, RunControl::default(), &mut |_| {}).unwrap()
    };
    let plain = run(&text);
    assert_eq!(plain.levels.len(), 2, "{}", plain.message);
    assert!(
        plain.message.ends_with("refine.tolerance"),
        "{}",
        plain.message
    );
    let waits = run(&uniform(Some(l / (0.5 * (h[1] + h[2])))));
    assert_eq!(waits.levels.len(), 3, "{}", waits.message);
    assert!(
        waits.message.ends_with("refine.tolerance"),
        "{}",
        waits.message
    );
    // Up to its second level, the run is the plain one.
    assert_eq!(
        waits.levels[1].drape_coefficient,
        plain.levels[1].drape_coefficient
    );
    let coarse = run(&uniform(Some(l / (0.5 * h[2]))));
    assert_eq!(coarse.levels.len(), 3, "{}", coarse.message);
    let asked = format!(
        "mean edge {:.2} mm against {:.2} mm): not converged",
        1e3 * h[2],
        0.5e3 * h[2]
    );
    assert!(coarse.message.ends_with(&asked), "{}", coarse.message);
}

/// Each key out of its range, and a mesh of order 2, refused by name.
#[test]
fn bad_refine_keys_are_refused_by_name() {
    let base = common::fabric("[time]\nsegments = [{ steps = 1, dt = 1.0e-3 }]\n");
    let lines = base.lines().count();
    let at = |extra: &str, line: usize, key: &str, says: &[&str]| {
        assert_error(
            &format!("{base}\n[refine]\n{extra}\n"),
            lines + 3 + line,
            key,
            says,
        );
    };
    at(
        "levels = 0",
        0,
        "refine.levels",
        &["must be 1 to 4", "not 0"],
    );
    at("levels = 5", 0, "refine.levels", &["not 5"]);
    at("tolerance = -0.1", 0, "refine.tolerance", &[">= 0", "-0.1"]);
    at("resolution = -4.0", 0, "refine.resolution", &[">= 0", "-4"]);
    at("fraction = 0.0", 0, "refine.fraction", &["(0, 1]", "not 0"]);
    at("fraction = 1.5", 0, "refine.fraction", &["not 1.5"]);
    let t6 = base.replace("[mesh]", "[mesh]\norder = 2");
    let message = common::build(
        &format!("{t6}\n[refine]\nlevels = 1\n"),
        Path::new("test.toml"),
    )
    .unwrap_err();
    assert!(
        message.contains("refine.where") && message.contains("linear triangles"),
        "{message}"
    );
    let _ = setup(&format!("{t6}\n[refine]\nlevels = 1\nwhere = \"all\"\n"));
    // A value not among a choice's: the message names it and the choices.
    let refused = |extra: &str, words: &[&str]| {
        let message = common::build(
            &format!("{base}\n[refine]\n{extra}\n"),
            Path::new("test.toml"),
        )
        .unwrap_err();
        assert!(words.iter().all(|w| message.contains(w)), "{message}");
    };
    refused("where = \"everywhere\"", &["everywhere", "all"]);
    refused("indicator = \"sag\"", &["sag", "bending", "chord"]);
    refused("also = [\"rim\", \"hem\"]", &["hem", "rim", "contact"]);
    // Elements per bending length, of a fabric without one.
    refused(
        "resolution = 4.0",
        &["refine.resolution", "bending rigidity", "weight"],
    );
    let _ = setup(&format!("{base}\n[refine]\nlevels = 3\nwhere = \"all\"\n"));
    let _ = setup(&format!("{base}\n[refine]\nindicator = \"chord\"\n"));
    let _ = setup(&format!(
        "{base}\n[refine]\nalso = [\"rim\", \"contact\"]\n"
    ));
}

/// A finer level's settle is one increment at the full load from the
/// carried shape; where Newton cannot solve it, it is relaxed in
/// pseudo-time at once rather than halved (halving would unload the
/// carried shape). The tester as written no longer needs it (its finer
/// levels settle in 75 and 33 iterations); with a membrane ten times
/// stiffer and the weight put on in one increment, its first finer level
/// fails in 200 iterations: with no halvings allowed it settles, relaxed
/// (7 pseudo-steps), with no cut-back.
#[test]
fn a_level_newton_cannot_settle_is_relaxed_without_halving() {
    let text = tester()
        .replace(
            "max_iterations = 200",
            "max_iterations = 200\nmax_cutbacks = 0",
        )
        .replace("steps = 6", "steps = 1")
        .replace("youngs_modulus = 2.0e6", "youngs_modulus = 2.0e7");
    assert!(text.contains("max_cutbacks = 0") && text.contains("steps = 1\n"));
    assert!(text.contains("youngs_modulus = 2.0e7"));
    let out = temp_dir("levels-relaxed");
    let summary =
        run_levels(&text, &out, RunControl::default(), &mut |_| {}).expect("the level is relaxed");
    assert_eq!(summary.levels.len(), 3);
    assert_eq!(summary.cutbacks, 0);

    // The same run counted for a front end (`drape::progress`): the
    // counts of each step, read as it converges, hold every Newton
    // iteration (failed solves too), the relaxed level's pseudo-steps,
    // and the level with its triangles; the run is the same to the bit.
    let counts = Arc::new(StepProgress::new());
    let control = RunControl {
        progress: Some(&counts),
        ..RunControl::default()
    };
    let counted = temp_dir("levels-relaxed-counted");
    let mut readings = Vec::new();
    let again = run_levels(&text, &counted, control, &mut |info| {
        readings.push((info.step, info.iterations, counts.read()));
    })
    .expect("the level is relaxed");
    assert_eq!(
        std::fs::read(out.join("history.csv")).unwrap(),
        std::fs::read(counted.join("history.csv")).unwrap()
    );
    assert_eq!(again.newton_iterations, summary.newton_iterations);
    assert_eq!(readings.len(), summary.steps);
    for (k, (step, iterations, r)) in readings.iter().enumerate() {
        assert_eq!(r.steps, k, "step {step}");
        assert!(r.iterations >= *iterations && r.solves >= 1, "{r:?}");
    }
    // The last two steps are the finer levels' increments; one of them
    // failed its plain solve and was relaxed.
    let levels = &readings[readings.len() - 2..];
    for (k, (_, _, r)) in levels.iter().enumerate() {
        assert_eq!(r.level, k + 1);
        assert_eq!(r.elements, summary.levels[k + 1].elements);
    }
    let relaxed = levels
        .iter()
        .find(|(_, _, r)| r.pseudo_steps > 0)
        .unwrap_or_else(|| panic!("a relaxed level: {readings:?}"));
    assert!(relaxed.2.solves > relaxed.2.pseudo_steps, "{:?}", relaxed.2);
    assert!(relaxed.2.iterations > relaxed.1, "{:?}", relaxed);
    assert!(relaxed.2.residual.is_finite());
    assert_eq!(counts.read().steps, summary.steps);
    // Every iteration is counted once in the summary: the converged
    // steps' in `newton_iterations`, the solves' thrown away (the level's
    // failed plain solve, 200 iterations, among them) besides.
    let done: usize = readings.iter().map(|(_, _, r)| r.iterations).sum();
    let discarded = summary.newton_iterations_discarded;
    assert_eq!(done, summary.newton_iterations + discarded);
    assert!(discarded >= 200, "{discarded} discarded");
    assert_eq!(again.newton_iterations_discarded, discarded);
}
