//! The field frames of a run, written by a thread of their own while the
//! run loop goes on: they arrive complete and in step order, the
//! collection lists only frames on disk, an error on that thread ends the
//! run naming the file, and an interrupted run's checkpoint, collection
//! and frames agree.

mod common;

use common::{column, fabric, read_history, setup, temp_dir};
use drape::output::pvd::frame_relative_path;
use drape::simulation::{self, Checkpoint, RunControl, RunError, checkpoint_path};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// An 8 x 8 fabric falling onto a plane (so that contact forces are part
/// of the frames), `steps` steps, a frame every `every` steps.
fn scenario(steps: usize, every: usize) -> drape::setup::Setup {
    let text = fabric(&format!(
        r#"
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, -0.002]
normal = [0.0, 0.0, 1.0]
[contact]
method = "penalty"
penalty = 5.0e4
[time]
beta = 1.0
gamma = 1.5
segments = [{{ steps = {steps}, dt = 2.0e-3 }}]
[output]
every = {every}
"#
    ));
    setup(&text.replace("divisions = [20, 20]", "divisions = [8, 8]"))
}

/// The collection's `(timestep, file)` entries, in file order.
fn collection(out: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert!(text.ends_with("</VTKFile>\n"), "fields.pvd incomplete");
    let attr = |line: &str, name: &str| {
        let key = format!(" {name}=\"");
        let start = line.find(&key).unwrap() + key.len();
        let len = line[start..].find('"').unwrap();
        line[start..start + len].to_string()
    };
    text.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet "))
        .map(|l| (attr(l, "timestep").parse().unwrap(), attr(l, "file")))
        .collect()
}

/// The time stored in a frame, after checking that the file is complete.
fn frame_time(path: &Path) -> f64 {
    let bytes = std::fs::read(path).unwrap();
    assert!(
        bytes.ends_with(b"</VTKFile>\n"),
        "{} truncated",
        path.display()
    );
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]).into_owned();
    let key = "Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">";
    let start = head.find(key).unwrap() + key.len();
    let len = head[start..].find('<').unwrap();
    head[start..start + len].parse().unwrap()
}

/// Every frame the collection names is complete on disk (under `fields`,
/// which may have been moved) and holds the time the collection gives it;
/// returns the steps named, in order.
fn check_collection(out: &Path, fields: &str) -> Vec<usize> {
    collection(out)
        .iter()
        .map(|(time, file)| {
            let name = file.strip_prefix("fields/").unwrap();
            let t = frame_time(&out.join(fields).join(name));
            assert_eq!(t.to_bits(), time.to_bits(), "{file}");
            let step: usize = name
                .strip_prefix("step_")
                .and_then(|s| s.strip_suffix(".vtu"))
                .unwrap()
                .parse()
                .unwrap();
            assert_eq!(file, &frame_relative_path(step as u64));
            step
        })
        .collect()
}

/// A completed run: the initial frame, one every 3 steps and the last
/// step's, in step order, each complete and at the history's time of its
/// step; no temporary file is left, and the summary reports the writer
/// thread's time.
#[test]
fn frames_arrive_complete_and_in_step_order() {
    let s = scenario(31, 3);
    let out = temp_dir("frames-order");
    let summary = simulation::run(&s, &out, &mut |_| {}).unwrap();
    let steps = check_collection(&out, "fields");
    let mut expected: Vec<usize> = (0..=31).step_by(3).collect();
    expected.push(31);
    assert_eq!(steps, expected);
    let (header, rows) = read_history(&out);
    let times = column(&header, &rows, "time");
    for ((time, _), step) in collection(&out).iter().zip(&steps) {
        assert_eq!(time.to_bits(), times[*step].to_bits(), "step {step}");
    }
    let mut files: Vec<String> = std::fs::read_dir(out.join("fields"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let listed: Vec<String> = expected
        .iter()
        .map(|&k| frame_relative_path(k as u64)["fields/".len()..].to_string())
        .collect();
    assert_eq!(files, listed, "fields/ holds exactly the listed frames");
    assert!(summary.output_thread_seconds > 0.0);
    assert!(summary.output_seconds >= 0.0);
}

/// The frames' directory replaced by a file in the middle of the run: the
/// writer thread's failure ends the run with an I/O error naming the
/// frame, and the collection still lists only frames that are complete
/// (in the moved directory), in order.
#[test]
fn an_error_on_the_writer_thread_ends_the_run_naming_the_file() {
    let s = scenario(30, 1);
    let out = temp_dir("frames-error");
    let fields = out.join("fields");
    let mut observer = |info: &simulation::StepInfo| {
        if info.step == 10 {
            std::fs::rename(&fields, out.join("fields.moved")).unwrap();
            std::fs::write(&fields, "not a directory").unwrap();
        }
    };
    let error = simulation::run(&s, &out, &mut observer).unwrap_err();
    let RunError::Io { path, .. } = &error else {
        panic!("expected an I/O error, got {error}");
    };
    assert!(path.starts_with(&fields), "{error}");
    assert_eq!(path.extension().unwrap(), "vtu", "{error}");
    assert!(error.to_string().contains(&path.display().to_string()));
    let steps = check_collection(&out, "fields.moved");
    assert!(!steps.is_empty());
    assert_eq!(steps, (0..steps.len()).collect::<Vec<_>>());
    // The loop wrote the history up to the step at which it heard of the
    // error, at step 10 or later.
    let (_, rows) = read_history(&out);
    assert!(rows.len() >= 11, "{} rows", rows.len());
}

/// A run stopped after step 13 (as by Ctrl-C): its checkpoint lists
/// exactly the frames of the collection, all of them complete on disk,
/// the summary says "interrupted", and the run resumed from it ends with
/// the same history and last frame, to the byte, as an uninterrupted run.
#[test]
fn an_interrupted_run_has_its_checkpointed_frames_on_disk_and_resumes_exactly() {
    let s = scenario(31, 3);
    let whole = temp_dir("frames-whole");
    simulation::run(&s, &whole, &mut |_| {}).unwrap();

    let out = temp_dir("frames-interrupted");
    let stop = AtomicBool::new(false);
    let mut observer = |info: &simulation::StepInfo| {
        if info.step == 13 {
            stop.store(true, Ordering::SeqCst);
        }
    };
    let control = RunControl {
        stop: Some(&stop),
        resume: false,
        ..Default::default()
    };
    let result = simulation::run_with(&s, &out, &mut observer, control);
    assert!(
        matches!(result, Err(RunError::Interrupted { .. })),
        "{result:?}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"interrupted\""), "{summary}");

    let bytes = std::fs::read(checkpoint_path(&out)).unwrap();
    let bodies = s.model.contact().map_or(0, |c| c.bodies.len());
    let ck = Checkpoint::from_bytes(&bytes, s.model.dofs(), bodies, s.scenario_hash).unwrap();
    let steps = check_collection(&out, "fields");
    assert_eq!(steps, [0, 3, 6, 9, 12]);
    let listed: Vec<(f64, usize)> = collection(&out)
        .iter()
        .map(|(t, _)| *t)
        .zip(steps.iter().copied())
        .collect();
    assert_eq!(ck.frames, listed);

    let control = RunControl {
        stop: None,
        resume: true,
        ..Default::default()
    };
    simulation::run_with(&s, &out, &mut |_| {}, control).unwrap();
    let text = |dir: &Path| std::fs::read_to_string(dir.join("history.csv")).unwrap();
    assert_eq!(text(&out), text(&whole));
    assert_eq!(
        check_collection(&out, "fields"),
        check_collection(&whole, "fields")
    );
    let last = |dir: &Path| std::fs::read(dir.join(frame_relative_path(31))).unwrap();
    assert_eq!(last(&out), last(&whole));
}
