//! `drape test SCENARIO --specimens N`: a drape test of several specimens
//! (README, "The drape test"; SPEC §6.7).
//!
//! The specimens are planned by the library (`Scenario::specimens`) and
//! laid out by `drape_lab::drape_test`; the local engine runs each as a
//! child `drape run` of this binary on one thread (`RAYON_NUM_THREADS=1`:
//! no rayon workers and no `par` helper), `--jobs` at a time, the rest
//! queued. A child process, rather than a thread here: each specimen is
//! then exactly `drape run` on its directory (its own lock, checkpoint,
//! summary, signals), one specimen's crash cannot take the others with
//! it, and one process's pools and helper thread are not shared between
//! specimens (measured: docs/performance.md, "The drape test"). Ray and
//! Dask run them through the Python package's sweep engines
//! (`python3 -m drape test`).

use crate::{Failure, signals};
use anyhow::{Context, anyhow};
use drape::scenario::{Scenario, SpecimenPlan};
use drape_lab::drape_test::{self as lab, Outcome, Prior};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

/// Where the specimens run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// Child processes on this machine.
    Local,
    /// Ray tasks (through `python3 -m drape test`).
    Ray,
    /// Dask futures (through `python3 -m drape test`).
    Dask,
}

/// `drape test`'s arguments.
#[derive(clap::Args)]
pub struct TestArgs {
    /// The scenario file (TOML); its `[test]` table says how the specimens
    /// differ (README, "The drape test").
    pub scenario: PathBuf,
    /// How many specimens (1 to 10000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub specimens: u32,
    /// Output directory [default: ./out/<scenario stem>-test].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Specimens at once (local), or the CPUs of a local Ray or Dask
    /// cluster [default: the CPUs here].
    #[arg(long, value_name = "J", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub jobs: Option<u32>,
    /// Where the specimens run.
    #[arg(long, value_enum, default_value_t = Engine::Local)]
    pub engine: Engine,
    /// The Ray or Dask cluster (its workers must see DIR at the same path);
    /// without it a local one is started.
    #[arg(long, value_name = "ADDR")]
    pub address: Option<String>,
    /// The test's seed: the same seed gives the same specimens.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Print nothing but errors and the result line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `drape test`.
pub fn run(a: TestArgs) -> Result<(), Failure> {
    signals::install();
    let input = |e: anyhow::Error| Failure::Input(e);
    if a.address.is_some() && a.engine == Engine::Local {
        return Err(input(anyhow!(
            "--address names a Ray or Dask cluster: use it with --engine ray or --engine dask"
        )));
    }
    let out = a.out.clone().unwrap_or_else(|| {
        let stem = a
            .scenario
            .file_stem()
            .map_or("test".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(format!("{stem}-test"))
    });
    if a.engine != Engine::Local {
        return delegate(&a, &out);
    }
    let (scenario, text) = Scenario::read(&a.scenario)?;
    let plans = scenario.specimens(&a.scenario, &text, a.specimens as usize, a.seed)?;
    // Every specimen builds as the first does (the perturbations' ranges
    // are checked with the [test] table): a bad scenario is refused before
    // anything runs.
    if let Some(first) = plans.first() {
        Scenario::parse(&first.text, &a.scenario)?.build(&a.scenario, &first.text)?;
    }
    signals::setup_done();
    let out = std::path::absolute(&out).unwrap_or(out);
    lab::take_directory(&out).map_err(input)?;
    let jobs = a.jobs.map_or_else(cpus, |j| j as usize);
    let mut outcomes = Vec::new();
    let mut todo = Vec::new();
    for plan in &plans {
        match lab::prior(&lab::specimen_dir(&out, plan), &plan.text) {
            Prior::Completed => outcomes.push(Outcome {
                index: plan.index,
                status: "completed".into(),
                message: String::new(),
            }),
            prior => todo.push((plan, prior)),
        }
    }
    if !a.quiet {
        eprintln!(
            "{} specimens: {} done before, {} to run, {} at a time on one thread each",
            plans.len(),
            outcomes.len(),
            todo.len(),
            jobs.min(todo.len()).max(1)
        );
    }
    outcomes.extend(run_local(&out, &todo, jobs, a.quiet));
    let title = scenario.title.clone().unwrap_or_else(|| {
        a.scenario
            .file_stem()
            .map_or(String::new(), |s| s.to_string_lossy().into_owned())
    });
    let info = lab::TestInfo {
        scenario: &a.scenario,
        title: &title,
        seed: a.seed,
        plans: &plans,
    };
    let value = lab::report(&out, &info, &outcomes).map_err(Failure::Run)?;
    println!("{}", value["message"].as_str().unwrap_or(""));
    println!("results in {}", out.join(lab::TEST_JSON).display());
    let rows = value["specimens"].as_array().cloned().unwrap_or_default();
    let unfinished: Vec<_> = rows.iter().filter(|r| r["status"] != "completed").collect();
    for r in &unfinished {
        eprintln!(
            "specimen {:04} {}: {}",
            r["specimen"].as_u64().unwrap_or(0),
            r["status"].as_str().unwrap_or(""),
            r["message"].as_str().unwrap_or("")
        );
    }
    if signals::STOP.load(Ordering::SeqCst) {
        return Err(Failure::Interrupted(anyhow!(
            "the specimens done so far are in {}; run the same command again to finish",
            out.join(lab::TEST_JSON).display()
        )));
    }
    match unfinished.len() {
        0 => Ok(()),
        n => Err(Failure::Run(anyhow!(
            "{n} of {} specimens did not complete",
            rows.len()
        ))),
    }
}

/// The CPUs this process may use.
fn cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Runs `todo` as child `drape run` processes, `jobs` at a time; each
/// specimen's outcome. A stop (Ctrl-C, SIGTERM) starts no more, and passes
/// SIGINT to the running ones, which end after their step with a
/// checkpoint.
fn run_local(
    out: &Path,
    todo: &[(&SpecimenPlan, Prior)],
    jobs: usize,
    quiet: bool,
) -> Vec<Outcome> {
    let next = AtomicUsize::new(0);
    let finished = AtomicBool::new(false);
    let running: Mutex<Vec<u32>> = Mutex::new(Vec::new());
    let outcomes = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..jobs.min(todo.len()))
            .map(|_| {
                scope.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        let Some(&(plan, prior)) = todo.get(i) else {
                            break;
                        };
                        if signals::STOP.load(Ordering::SeqCst) {
                            break;
                        }
                        let outcome = run_one(out, plan, prior, &running);
                        if !quiet {
                            let why = if outcome.message.is_empty() {
                                String::new()
                            } else {
                                format!(": {}", outcome.message)
                            };
                            eprintln!("specimen {} {}{why}", plan.name(), outcome.status);
                        }
                        lock(&outcomes).push(outcome);
                    }
                })
            })
            .collect();
        // Passes a stop on to the children while any runs.
        scope.spawn(|| {
            while !finished.load(Ordering::SeqCst) {
                if signals::STOP.load(Ordering::SeqCst) {
                    for &pid in lock(&running).iter() {
                        interrupt(pid);
                    }
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        });
        for worker in workers {
            // A worker's panic is a bug of this file's; its specimen is
            // then reported as not started.
            let _ = worker.join();
        }
        finished.store(true, Ordering::SeqCst);
    });
    outcomes.into_inner().unwrap_or_else(|e| e.into_inner())
}

/// The mutex's value, poisoned or not (a panicking worker leaves the
/// list itself whole).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// SIGINT to the child `pid`.
#[cfg(unix)]
fn interrupt(pid: u32) {
    // SAFETY: kill(2) on a child we started and have not reaped.
    unsafe {
        libc::kill(pid as libc::pid_t, libc::SIGINT);
    }
}

#[cfg(not(unix))]
fn interrupt(_pid: u32) {}

/// One specimen: its scenario laid in its directory and `drape run` on it
/// (resumed where it was interrupted), on one thread.
fn run_one(out: &Path, plan: &SpecimenPlan, prior: Prior, running: &Mutex<Vec<u32>>) -> Outcome {
    let dir = lab::specimen_dir(out, plan);
    let failed = |message: String| Outcome {
        index: plan.index,
        status: "failed".into(),
        message,
    };
    let scenario = match lab::place_scenario(out, plan) {
        Ok(p) => p,
        Err(e) => return failed(format!("{e:#}")),
    };
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(e) => return failed(format!("cannot find the drape binary to run it: {e}")),
    };
    let mut command = Command::new(exe);
    command.arg("run").arg("--quiet");
    match prior {
        Prior::Interrupted => command.arg("--resume").arg(&dir),
        _ => command.arg(&scenario).arg("--out").arg(&dir),
    };
    command
        .env("RAYON_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let child: Child = match command.spawn() {
        Ok(c) => c,
        Err(e) => return failed(format!("cannot start drape run: {e}")),
    };
    let pid = child.id();
    running.lock().unwrap_or_else(|e| e.into_inner()).push(pid);
    let output = child.wait_with_output();
    running
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|&p| p != pid);
    let stderr = match &output {
        Ok(o) => String::from_utf8_lossy(&o.stderr).trim().to_string(),
        Err(e) => e.to_string(),
    };
    let summary = lab::summary(&dir);
    let status = summary
        .as_ref()
        .and_then(|s| s["status"].as_str().map(str::to_string));
    let message = summary
        .as_ref()
        .and_then(|s| s["message"].as_str().map(str::to_string))
        .unwrap_or_default();
    let success = output.as_ref().is_ok_and(|o| o.status.success());
    match status.as_deref() {
        Some("completed") if success => Outcome {
            index: plan.index,
            status: "completed".into(),
            message: String::new(),
        },
        Some("interrupted") => Outcome {
            index: plan.index,
            status: "interrupted".into(),
            message,
        },
        _ => failed(
            stderr
                .lines()
                .rev()
                .find(|l| l.starts_with("error"))
                .map(|l| l.trim_start_matches("error: ").to_string())
                .filter(|l| !l.is_empty())
                .unwrap_or(if message.is_empty() { stderr } else { message }),
        ),
    }
}

/// `--engine ray|dask`: the Python package's `python -m drape test`, with
/// the same arguments; its exit status is this one's.
fn delegate(a: &TestArgs, out: &Path) -> Result<(), Failure> {
    let python = std::env::var_os("DRAPE_PYTHON").unwrap_or_else(|| "python3".into());
    let engine = match a.engine {
        Engine::Ray => "ray",
        Engine::Dask => "dask",
        Engine::Local => "local",
    };
    let why = |detail: String| {
        Failure::Input(anyhow!(
            "--engine {engine} runs the specimens through drape's Python package (`{} -m drape test`), which cannot be used here: {detail}; install it (pip install \"./crates/drape-py[{engine}]\"), or set DRAPE_PYTHON to the Python that has it, or use --engine local",
            python.to_string_lossy()
        ))
    };
    let probe = Command::new(&python)
        .args(["-c", "import drape._drape"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| why(format!("cannot start {}: {e}", python.to_string_lossy())))?;
    if !probe.status.success() {
        let err = String::from_utf8_lossy(&probe.stderr);
        return Err(why(err
            .lines()
            .last()
            .unwrap_or("import drape failed")
            .to_string()));
    }
    // From here a Ctrl-C reaches Python's test too (one process group),
    // which ends its specimens and writes test.json; this process waits
    // for it and exits with its code.
    signals::setup_done();
    let mut command = Command::new(&python);
    command
        .args(["-m", "drape", "test"])
        .arg(&a.scenario)
        .arg("--specimens")
        .arg(a.specimens.to_string())
        .arg("--out")
        .arg(out)
        .arg("--engine")
        .arg(engine)
        .arg("--seed")
        .arg(a.seed.to_string());
    if let Some(j) = a.jobs {
        command.arg("--jobs").arg(j.to_string());
    }
    if let Some(address) = &a.address {
        command.arg("--address").arg(address);
    }
    let status = command
        .status()
        .with_context(|| format!("cannot start {}", python.to_string_lossy()))
        .map_err(Failure::Input)?;
    match status.code() {
        Some(0) => Ok(()),
        Some(2) => Err(Failure::Input(anyhow!(
            "{} -m drape test refused its input (above)",
            python.to_string_lossy()
        ))),
        Some(130) | None => Err(Failure::Interrupted(anyhow!(
            "interrupted; run the same command again to finish"
        ))),
        Some(_) => Err(Failure::Run(anyhow!(
            "some specimens did not complete (above)"
        ))),
    }
}
