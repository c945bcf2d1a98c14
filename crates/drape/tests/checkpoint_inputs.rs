//! A resume refuses anything changed (issue 19): the checkpoint records
//! the hash of every input file — the mesh, the obstacles' meshes — and a
//! resume after one of them changed, or went missing, is refused naming
//! it; unchanged, the resumed run reproduces the uninterrupted one bit for
//! bit. A checkpoint of version 3 (no file hashes) resumes as before. A
//! checkpoint whose checksum is valid but whose values are not — or that
//! is cut short — is refused naming the checkpoint file and the field.

mod common;

use common::temp_dir;
use drape::input::fnv1a;
use drape::output::pvd::frame_relative_path;
use drape::scenario::Scenario;
use drape::setup::Setup;
use drape::simulation::{
    self, Checkpoint, Front, RunControl, RunError, check_resume_inputs, checkpoint_path,
};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Scheduled steps of the runs, and the step the interrupted run stops at.
const STEPS: usize = 31;
const STOP_AT: usize = 13;

/// An `n` x `n` square plate of `size` (m) at z = 0 as an OBJ file, two
/// triangles per square, oriented along +z.
fn plate_obj(n: usize, size: f64) -> String {
    let mut text = String::from("# a square plate\n");
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (size * i as f64 / n as f64, size * j as f64 / n as f64);
            text.push_str(&format!("v {x} {y} 0\n"));
        }
    }
    let node = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            text.push_str(&format!("f {a} {b} {c}\nf {a} {c} {d}\n"));
        }
    }
    text
}

/// A closed box from `lo` to `hi` as an OBJ file, its faces oriented
/// outwards.
fn box_obj(lo: [f64; 3], hi: [f64; 3]) -> String {
    let mut text = String::new();
    for (x, y, z) in [
        (lo[0], lo[1], lo[2]),
        (hi[0], lo[1], lo[2]),
        (hi[0], hi[1], lo[2]),
        (lo[0], hi[1], lo[2]),
        (lo[0], lo[1], hi[2]),
        (hi[0], lo[1], hi[2]),
        (hi[0], hi[1], hi[2]),
        (lo[0], hi[1], hi[2]),
    ] {
        text.push_str(&format!("v {x} {y} {z}\n"));
    }
    text.push_str(
        "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n\
         f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n",
    );
    text
}

/// A folder with a plate mesh (`plate.obj`), a box obstacle mesh
/// (`block.obj`) under its middle and the scenario (`drop.toml`) that drops
/// the plate onto the box, with a checkpoint every 10 steps and a frame
/// every 3; contact by `contact` (the `[contact]` table's keys).
struct Case {
    dir: common::TempDir,
    scenario: PathBuf,
    plate: PathBuf,
    block: PathBuf,
}

impl Case {
    fn new(name: &str) -> Self {
        let contact = "method = \"penalty\"\npenalty = 5.0e4";
        Self::with_contact(name, contact, ([0.05, 0.05, -0.1], [0.15, 0.15, -0.002]))
    }

    /// The case with the box between `corners` and `contact`.
    fn with_contact(name: &str, contact: &str, corners: ([f64; 3], [f64; 3])) -> Self {
        let dir = temp_dir(name);
        let plate = dir.join("plate.obj");
        let block = dir.join("block.obj");
        std::fs::write(&plate, plate_obj(8, 0.2)).unwrap();
        std::fs::write(&block, box_obj(corners.0, corners.1)).unwrap();
        let scenario = dir.join("drop.toml");
        std::fs::write(
            &scenario,
            format!(
                r#"
[mesh]
shape = "file"
path = "plate.obj"
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "mesh"
path = "block.obj"
[contact]
{contact}
[time]
beta = 1.0
gamma = 1.5
segments = [{{ steps = {STEPS}, dt = 2.0e-3 }}]
[output]
every = 3
checkpoint_every = 10
"#
            ),
        )
        .unwrap();
        Self {
            dir,
            scenario,
            plate,
            block,
        }
    }

    /// The setup as the scenario and its files are now (as a resume reads
    /// them).
    fn setup(&self) -> Setup {
        let (scenario, source) = Scenario::read(&self.scenario).unwrap();
        scenario.build(&self.scenario, &source).unwrap()
    }

    /// A run into `out` stopped after step [`STOP_AT`] (as by Ctrl-C): its
    /// checkpoint is at that step.
    fn interrupted(&self, out: &Path) {
        self.interrupted_at(out, STOP_AT);
    }

    /// A run into `out` stopped after step `at`.
    fn interrupted_at(&self, out: &Path, at: usize) {
        let stop = AtomicBool::new(false);
        let mut observer = |info: &simulation::StepInfo| {
            if info.step == at {
                stop.store(true, Ordering::SeqCst);
            }
        };
        let control = RunControl {
            stop: Some(&stop),
            resume: false,
            ..Default::default()
        };
        let result = simulation::run_with(&self.setup(), out, &mut observer, control);
        assert!(
            matches!(result, Err(RunError::Interrupted { .. })),
            "{result:?}"
        );
    }
}

fn resume(setup: &Setup, out: &Path) -> Result<simulation::Summary, RunError> {
    resume_from(setup, out, Front::CommandLine)
}

fn resume_from(setup: &Setup, out: &Path, front: Front) -> Result<simulation::Summary, RunError> {
    let control = RunControl {
        resume: true,
        front,
        ..RunControl::default()
    };
    simulation::run_with(setup, out, &mut |_| {}, control)
}

fn history(dir: &Path) -> Vec<u8> {
    std::fs::read(dir.join("history.csv")).unwrap()
}

/// The refusal of a resume, and the history left as it was.
fn refused(setup: &Setup, out: &Path) -> String {
    let before = history(out);
    let e = match resume(setup, out) {
        Err(e @ RunError::Resume { .. }) => e.to_string(),
        other => panic!("expected the resume refused, got {other:?}"),
    };
    assert_eq!(history(out), before, "the history was touched: {e}");
    e
}

fn assert_says(message: &str, fragments: &[&str]) {
    for f in fragments {
        assert!(message.contains(f), "expected {f:?} in\n{message}");
    }
}

/// The uninterrupted run's outputs and the resumed run's agree to the byte:
/// the history, the collection and the last frame.
fn assert_same_outputs(a: &Path, b: &Path) {
    assert_eq!(history(a), history(b));
    let read = |dir: &Path, file: &str| std::fs::read(dir.join(file)).unwrap();
    assert_eq!(read(a, "fields.pvd"), read(b, "fields.pvd"));
    let pvd = String::from_utf8(read(a, "fields.pvd")).unwrap();
    let last = pvd
        .lines()
        .filter_map(|l| l.split("file=\"").nth(1))
        .next_back()
        .and_then(|f| f.split('"').next())
        .unwrap();
    assert_eq!(read(a, last), read(b, last));
}

/// The checkpoint records the plate's and the box's files; after either
/// changed (its bytes, with the same number of nodes) the resume is
/// refused naming it, both by the check before the scenario is built
/// (`check_resume_inputs`, which the command line runs) and by the run;
/// a missing file is refused by the former, naming it. Restored, the
/// resume reproduces the uninterrupted run to the byte.
#[test]
fn a_changed_input_file_refuses_the_resume_and_unchanged_ones_resume_bit_for_bit() {
    let case = Case::new("ckp-inputs");
    let whole = case.dir.join("whole");
    let uninterrupted = simulation::run(&case.setup(), &whole, &mut |_| {}).unwrap();
    let out = case.dir.join("out");
    case.interrupted(&out);

    let setup = case.setup();
    let keys: Vec<&str> = setup.inputs.iter().map(|i| i.key.as_str()).collect();
    assert_eq!(keys, ["mesh.path", "obstacle[0].path"]);
    let plate = std::fs::canonicalize(&case.plate).unwrap();
    let block = std::fs::canonicalize(&case.block).unwrap();
    assert_eq!(setup.inputs[0].path, plate);
    assert_eq!(setup.inputs[1].path, block);
    let bytes = std::fs::read(checkpoint_path(&out)).unwrap();
    assert_eq!(
        Checkpoint::recorded_inputs(&bytes).unwrap().as_ref(),
        Some(&setup.inputs)
    );
    check_resume_inputs(&out).unwrap();

    for (file, key) in [
        (&case.plate, "mesh.path"),
        (&case.block, "obstacle[0].path"),
    ] {
        let original = std::fs::read(file).unwrap();
        let path = std::fs::canonicalize(file).unwrap();
        let named = path.display().to_string();
        // A vertex moved by 1 mm: the same number of nodes.
        let text = String::from_utf8(original.clone()).unwrap();
        let moved = text
            .replacen("v 0.05 ", "v 0.051 ", 1)
            .replacen("v 0 0 0", "v 0.001 0 0", 1);
        assert_ne!(moved, text);
        std::fs::write(file, &moved).unwrap();
        let says = [
            named.as_str(),
            key,
            "has changed since the checkpoint was written",
            "Restore the file as it was, or start a fresh run",
        ];
        let early = check_resume_inputs(&out).unwrap_err().to_string();
        assert_says(&early, &says);
        let e = refused(&case.setup(), &out);
        assert_says(&e, &says);
        assert_says(&e, &[&checkpoint_path(&out).display().to_string()]);
        // Each front end names its own way to a fresh run (Python said
        // "without --resume").
        assert_says(&e, &["start a fresh run (without --resume)"]);
        match resume_from(&case.setup(), &out, Front::Python) {
            Err(e @ RunError::Resume { .. }) => {
                let e = e.to_string();
                assert_says(&e, &says);
                assert_says(&e, &["start a fresh run (resume=False)"]);
                assert!(!e.contains("--resume"), "{e}");
            }
            other => panic!("expected the resume refused, got {other:?}"),
        }
        // Missing: refused before the scenario would fail to read it.
        std::fs::remove_file(file).unwrap();
        let missing = check_resume_inputs(&out).unwrap_err().to_string();
        assert_says(
            &missing,
            &[
                named.as_str(),
                key,
                "recorded in the checkpoint cannot be read",
                "restore it as it was, or start a fresh run",
            ],
        );
        std::fs::write(file, &original).unwrap();
        check_resume_inputs(&out).unwrap();
    }

    let resumed = resume(&case.setup(), &out).unwrap();
    assert_same_outputs(&whole, &out);
    // The summary's linear-solver counts are the whole run's, as its
    // Newton iterations are (issue 34: they were the last session's).
    assert_eq!(resumed.linear, uninterrupted.linear);
    assert_eq!(resumed.newton_iterations, uninterrupted.newton_iterations);
}

/// The same file as version 3 wrote it: without the input files (and
/// without version 5's friction dissipation and linear counts), sealed.
fn as_version_3(bytes: &[u8]) -> Vec<u8> {
    let inputs = 8 + 4 + 8;
    let count = u64::from_le_bytes(bytes[inputs..inputs + 8].try_into().unwrap());
    let mut at = inputs + 8;
    for _ in 0..count {
        for _ in 0..2 {
            let n = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
            at += 4 + n as usize;
        }
        at += 8;
    }
    // Version 8's levels and pending sub-steps follow the inputs: no
    // refinement, no level, nothing pending (three counts of 0).
    assert_eq!(bytes[at..at + 24], [0; 24], "no levels");
    at += 24;
    // Version 12's plastic curvatures end the body (none here: a count of
    // 0), after version 11's discarded iterations (a u64), after version
    // 9's cavities (none here: a count of 0), after version 7's
    // self-contact layout (none: a count of 0), after version 6's kept
    // linear-solver state: a direct solve keeps nothing, its two flags 0.
    let plastic = bytes.len() - 8 - 8;
    assert_eq!(bytes[plastic..plastic + 8], [0; 8], "no plastic curvatures");
    let gas = plastic - 8 - 8;
    assert_eq!(bytes[gas..gas + 8], [0; 8], "no cavities");
    let layout = gas - 8;
    assert_eq!(bytes[layout..layout + 8], [0; 8], "no self-contact layout");
    let kept = layout - 2;
    assert_eq!(bytes[kept..kept + 2], [0, 0], "a direct run keeps nothing");
    let mut body = bytes[..inputs].to_vec();
    body.extend_from_slice(&bytes[at..kept]);
    // Magic, version, 4 header u64, 4 counters u64, 5 counter fields,
    // segment, step size, still steps, time, external work, persistence:
    // then the friction dissipation, which version 3 did not have.
    let friction = 8 + 4 + 8 * 4 + 8 * 4 + 8 * 5 + 8 * 3 + 8 * 2 + 8;
    body.drain(friction..friction + 8 + 8 * 7);
    body[8..12].copy_from_slice(&3u32.to_le_bytes());
    let hash = fnv1a(&body);
    body.extend_from_slice(&hash.to_le_bytes());
    body
}

/// A checkpoint of version 3 records no input files: it resumes as
/// before, without a file check (a comment added to the mesh file does not
/// refuse it), to the same bytes as the uninterrupted run.
#[test]
fn a_version_3_checkpoint_resumes_without_the_file_check() {
    let case = Case::new("ckp-v3");
    let whole = case.dir.join("whole");
    simulation::run(&case.setup(), &whole, &mut |_| {}).unwrap();
    let out = case.dir.join("out");
    // Version 3 knew no pending halves of a cut-back step: stopped where a
    // whole scheduled step ended (a row of the schedule's dt).
    let (header, rows) = common::read_history(&whole);
    let dt = common::column(&header, &rows, "dt");
    let at = (5..dt.len()).find(|&k| dt[k] == 2.0e-3).unwrap();
    case.interrupted_at(&out, at);
    let path = checkpoint_path(&out);
    let v3 = as_version_3(&std::fs::read(&path).unwrap());
    assert_eq!(Checkpoint::recorded_inputs(&v3).unwrap(), None);
    std::fs::write(&path, v3).unwrap();
    // The geometry is the same, the bytes are not.
    let mut text = std::fs::read_to_string(&case.plate).unwrap();
    text.push_str("# edited\n");
    std::fs::write(&case.plate, text).unwrap();
    check_resume_inputs(&out).unwrap();
    resume(&case.setup(), &out).unwrap();
    assert_same_outputs(&whole, &out);
}

/// A checkpoint whose checksum is valid but whose values are not is
/// refused naming the checkpoint file and the field, before the history is
/// touched: counters past the schedule or against each other, a time
/// beyond the end, Newton iterations no run could have; so is one cut
/// short (its checksum fails; sealed again, the field it ends in is named)
/// and one whose listed frames are not on disk. The good one then resumes
/// bit for bit.
#[test]
fn a_forged_or_truncated_checkpoint_is_refused_naming_the_field() {
    let case = Case::new("ckp-forged");
    let whole = case.dir.join("whole");
    simulation::run(&case.setup(), &whole, &mut |_| {}).unwrap();
    let out = case.dir.join("out");
    case.interrupted(&out);
    let setup = case.setup();
    let path = checkpoint_path(&out);
    let named = path.display().to_string();
    let good = std::fs::read(&path).unwrap();
    let bodies = 1;
    let ck =
        Checkpoint::from_bytes(&good, setup.model.dofs(), bodies, setup.scenario_hash).unwrap();
    // (Some steps are cut back: more converged steps than scheduled; the
    // stop came inside one, whose halves left the checkpoint keeps and
    // the resume below takes.)
    assert!(ck.counters.step >= STOP_AT, "{:?}", ck.counters);
    assert!(!ck.pending.is_empty(), "{:?}", ck.counters);
    let done = ck.counters.scheduled_done;
    assert_eq!(Checkpoint::read(&good, &setup).unwrap(), ck);

    let forged = |change: &dyn Fn(&mut Checkpoint), says: &str| {
        let mut bad = ck.clone();
        change(&mut bad);
        std::fs::write(&path, bad.to_bytes()).unwrap();
        let e = refused(&setup, &out);
        assert_says(&e, &[&named, "the checkpoint is unusable", says]);
    };
    forged(
        &|c| c.counters.step = usize::MAX,
        "is not the converged steps 18446744073709551615",
    );
    forged(
        &|c| {
            c.counters.scheduled_done = STEPS + 5;
            c.counters.step = STEPS + 5;
            c.counters.since_frame = STEPS + 5 - c.counters.last_written;
        },
        "scheduled steps done 36 beyond the schedule's 31",
    );
    forged(
        &|c| c.counters.scheduled_done = done - 1,
        &format!("is not where {} scheduled steps end", done - 1),
    );
    forged(&|c| c.state.time = 5.0, "time 5 beyond the schedule's end");
    forged(
        &|c| c.counters.iterations = usize::MAX,
        "Newton iterations 18446744073709551615 more than",
    );
    forged(
        &|c| c.counters.still_steps = 3,
        "still steps 3 without a rest criterion",
    );
    forged(&|c| c.counters.segment = 2, "segment 2 with fixed steps");
    forged(
        &|c| c.state.positions[7] = f64::NAN,
        "positions[7] NaN is not finite",
    );
    forged(
        &|c| c.frames.push((c.state.time, c.counters.step + 1)),
        &format!(
            "step of the last frame {} is not the last listed frame's step {}",
            ck.counters.last_written,
            ck.counters.step + 1
        ),
    );

    // Cut short: the checksum fails.
    std::fs::write(&path, &good[..good.len() / 2]).unwrap();
    let e = refused(&setup, &out);
    assert_says(&e, &[&named, "damaged or truncated"]);
    // Cut short and sealed again: the field it ends in.
    let mut body = good[..good.len() / 2].to_vec();
    let hash = fnv1a(&body);
    body.extend_from_slice(&hash.to_le_bytes());
    std::fs::write(&path, body).unwrap();
    let e = refused(&setup, &out);
    assert_says(&e, &[&named, "truncated in "]);

    // A frame it lists deleted.
    std::fs::write(&path, &good).unwrap();
    let frame = out.join(frame_relative_path(3));
    let kept = std::fs::read(&frame).unwrap();
    std::fs::remove_file(&frame).unwrap();
    let e = refused(&setup, &out);
    assert_says(
        &e,
        &[
            &named,
            &format!("the frame {} it lists is missing", frame.display()),
        ],
    );
    std::fs::write(&frame, kept).unwrap();

    resume(&setup, &out).unwrap();
    assert_same_outputs(&whole, &out);
}

/// With Lagrange multipliers, a checkpoint taken while nodes are held on
/// the box (their body and face, their multipliers) passes every check
/// and resumes to the same bytes as the uninterrupted run. (The plate
/// lands flat on a box wider than itself.)
#[test]
fn a_run_with_multipliers_resumes_bit_for_bit() {
    let block = ([-0.05, -0.05, -0.1], [0.25, 0.25, -0.002]);
    let case = Case::with_contact("ckp-lagrange", "method = \"lagrange\"", block);
    let whole = case.dir.join("whole");
    simulation::run(&case.setup(), &whole, &mut |_| {}).unwrap();
    let out = case.dir.join("out");
    case.interrupted(&out);
    let setup = case.setup();
    let ck = Checkpoint::read(&std::fs::read(checkpoint_path(&out)).unwrap(), &setup).unwrap();
    let contact = ck.state.contact.as_ref().unwrap();
    assert!(contact.active.iter().any(Option::is_some), "no node held");
    assert!(contact.multipliers.iter().any(|m| *m > 0.0));
    resume(&setup, &out).unwrap();
    assert_same_outputs(&whole, &out);
}
