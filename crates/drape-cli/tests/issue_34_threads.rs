//! Issues 30 and 34: one thread or two, the same answer to the last bit,
//! and no run that hangs. A run is the same computation whoever runs its
//! parts — every sum in an order fixed by the work, not by the threads —
//! so `history.csv` with `RAYON_NUM_THREADS=1` (how a sweep runs a case
//! per core) is byte for byte the two-thread one; and a mesh large enough
//! for rayon's loops (4,096 elements and more) with a one-worker pool
//! finishes, writing its frames and checkpoints, and ends on SIGINT.

mod issue_19_support;

use issue_19_support::{
    DRAPE, falling_sheet, scratch, send, spawn_run_with, summary, wait_for_history,
};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// The repository's root (two folders above this crate).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `drape run SCENARIO --out OUT --quiet` with `RAYON_NUM_THREADS =
/// threads`, started.
fn spawn_with_threads(scenario: &Path, out: &Path, threads: usize) -> Child {
    spawn_run_with(
        scenario,
        out,
        &[("RAYON_NUM_THREADS", &threads.to_string())],
    )
}

/// Waits for `child`, killing it (and failing the test) after `limit`:
/// a run that does not end has hung.
fn wait_within(mut child: Child, limit: Duration, what: &str) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running after {limit:?}: hung");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs `scenario` with one thread and with two (each within two
/// minutes) and compares their histories byte for byte.
fn same_history_on_one_and_two_threads(scenario: &Path, dir: &Path, name: &str) {
    let mut histories = Vec::new();
    for threads in [1, 2] {
        let out = dir.join(format!("{name}-{threads}"));
        let child = spawn_with_threads(scenario, &out, threads);
        let status = wait_within(child, Duration::from_secs(120), name);
        assert!(status.success(), "{name} on {threads} thread(s): {status}");
        histories.push(std::fs::read(out.join("history.csv")).expect("history.csv"));
    }
    assert!(
        histories[0] == histories[1],
        "{name}: the one-thread history differs from the two-thread one"
    );
}

/// `text` with its `[time]` segments replaced by `segments` and the
/// settling keys (adaptive, dt_max, rest) dropped, and the mesh `path`
/// made absolute against `base`.
fn shortened(text: &str, segments: &str, base: &Path) -> String {
    text.lines()
        .filter(|l| {
            !["adaptive", "dt_max", "rest"]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .map(|l| {
            if l.starts_with("segments") {
                format!("segments = {segments}")
            } else if let Some(rel) = l.strip_prefix("path = \"") {
                let rel = rel.trim_end_matches('"');
                format!("path = {:?}", base.join(rel))
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The pedestal example through the first contact (penalty, stress
/// projection), and the drape tester with bending (the settle
/// benchmark's scenario, the projected Newton) through its impact: the
/// same history on one thread and on two.
#[test]
fn one_thread_and_two_give_the_same_history() {
    let dir = scratch("threads");
    let pedestal = std::fs::read_to_string(root().join("examples/fabric-on-pedestal.toml"))
        .expect("the pedestal example");
    let path = dir.join("pedestal.toml");
    let segments = "[ { steps = 10, dt = 0.01 }, { steps = 60, dt = 1.0e-4 } ]";
    std::fs::write(
        &path,
        shortened(&pedestal, segments, &root().join("examples")),
    )
    .unwrap();
    same_history_on_one_and_two_threads(&path, &dir, "pedestal");

    let scenarios = root().join("crates/drape-bench/scenarios");
    let tester = std::fs::read_to_string(scenarios.join("settle-bending-t3.toml"))
        .expect("the settle benchmark");
    let path = dir.join("tester.toml");
    let segments = "[ { steps = 10, dt = 0.01 }, { steps = 40, dt = 1.0e-3 } ]";
    std::fs::write(&path, shortened(&tester, segments, &scenarios)).unwrap();
    same_history_on_one_and_two_threads(&path, &dir, "drape tester with bending");
}

/// A 5,000-element sheet (above the 4,096 from which the loops run on
/// rayon) falling, pinned at its edge, with frames and checkpoints every
/// two steps, `steps` steps long.
fn big_sheet(dir: &Path, steps: usize) -> PathBuf {
    let extra = "[[fix]]\nboundary = true\n[output]\nevery = 2\ncheckpoint_every = 2";
    falling_sheet(dir, [50, 50], steps, extra)
}

/// With one worker in rayon's pool — the main thread — the frame writer's
/// parallel loop once waited for that worker while it waited for the
/// frames (at the first frame or checkpoint): the run must end, with the
/// two-thread history.
#[test]
fn a_big_mesh_on_one_thread_does_not_hang() {
    let dir = scratch("one-thread-big");
    let scenario = big_sheet(&dir, 8);
    same_history_on_one_and_two_threads(&scenario, &dir, "5,000-element sheet");
}

/// Multigrid on a mesh of more than 20,000 nodes (where its loops run on
/// rayon's pool): a sheet of 22,801 nodes held at its edge, `linear =
/// "iterative"`, three steps. Its damping factor's power iteration summed
/// by rayon's own reduction, whose order follows the threads, and the
/// history differed from the second row on.
#[test]
fn multigrid_on_a_big_mesh_gives_the_same_history_on_one_and_two_threads() {
    let dir = scratch("multigrid");
    let extra = "[[fix]]\nboundary = true\n[solver]\nlinear = \"iterative\"\n[output]\nevery = 100";
    let scenario = falling_sheet(&dir, [150, 150], 3, extra);
    same_history_on_one_and_two_threads(&scenario, &dir, "multigrid sheet");
}

/// Under a one-CPU affinity (`taskset -c 0`, what a container limited to
/// one core gives) and without `RAYON_NUM_THREADS`, rayon's pool and the
/// helper thread see one CPU: the big sheet must end within two minutes,
/// its summary saying one thread, with the two-thread history byte for
/// byte.
#[test]
fn a_big_mesh_under_a_one_cpu_affinity_does_not_hang() {
    if Command::new("taskset").arg("--version").output().is_err() {
        eprintln!("taskset (util-linux) is not installed: the affinity case is not run here");
        return;
    }
    let dir = scratch("affinity");
    let scenario = big_sheet(&dir, 8);
    let two = dir.join("two");
    let status = wait_within(
        spawn_with_threads(&scenario, &two, 2),
        Duration::from_secs(120),
        "two threads",
    );
    assert!(status.success(), "two threads: {status}");
    let one = dir.join("one");
    let child = Command::new("taskset")
        .args(["-c", "0", DRAPE, "run"])
        .arg(&scenario)
        .arg("--out")
        .arg(&one)
        .arg("--quiet")
        .env_remove("RAYON_NUM_THREADS")
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn taskset");
    let status = wait_within(child, Duration::from_secs(120), "one-CPU affinity");
    assert!(status.success(), "one-CPU affinity: {status}");
    assert_eq!(summary(&one)["threads"], 1, "the run saw more than one CPU");
    let history = |out: &Path| std::fs::read(out.join("history.csv")).expect("history.csv");
    assert!(
        history(&one) == history(&two),
        "the one-CPU history differs from the two-thread one"
    );
}

/// SIGINT during a one-thread run of the big sheet ends it as on two
/// threads: exit 130 (128 + SIGINT), a summary saying "interrupted".
#[test]
fn sigint_ends_a_one_thread_run_of_a_big_mesh() {
    let dir = scratch("one-thread-sigint");
    let scenario = big_sheet(&dir, 100_000);
    let out = dir.join("out");
    let child = spawn_with_threads(&scenario, &out, 1);
    wait_for_history(&out, 4);
    send(&child, "INT");
    let status = wait_within(child, Duration::from_secs(60), "interrupted run");
    assert_eq!(status.code(), Some(130), "{status}");
    assert_eq!(summary(&out)["status"], "interrupted");
}
