//! `drape`: run, check and list membrane simulations (the README's command line).
//!
//! Exit codes: 0 success, 1 a run that failed (outputs up to the failure
//! are on disk), 2 bad input (scenario, mesh, command line).

use anyhow::Context;
use clap::{Parser, Subcommand};
use drape::human::human;
use drape::output::directory::{self, DirectoryError};
use drape::progress::{ProgressReading, StepProgress};
use drape::scenario::{Scenario, ScenarioError};
use drape::setup::Setup;
use drape::simulation::{self, Front, RunError, Session, StepInfo};
use drape_render::{Field, FrameSelect, View};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

mod alloc;
mod drape_test;
mod examples;
mod measure;
mod signals;

/// Transparent huge pages for the large arrays of big meshes (see [`alloc`]).
#[global_allocator]
static ALLOCATOR: alloc::HugePageAlloc = alloc::HugePageAlloc;

/// Membranes and fabrics in large displacement: positional finite elements,
/// Newmark dynamics, Newton–Raphson.
#[derive(Parser)]
#[command(name = "drape", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario and write history.csv, fields.pvd (+ fields/*.vtu) and summary.json.
    ///
    /// Progress (step, time, Newton iterations) goes to the terminal; the
    /// exit code is 1 when the run fails (everything computed so far is
    /// kept) and 2 when the scenario is invalid.
    ///
    /// Ctrl-C, SIGTERM or SIGHUP ends the current step, writes a checkpoint
    /// and the summary (status "interrupted") and exits with code 128 + the
    /// signal (130, 143 or 129); `--resume
    /// DIR` continues from the newest checkpoint in DIR, and refuses if
    /// the scenario or a file it reads (the mesh, an obstacle's mesh) has
    /// changed.
    Run {
        /// The scenario file (TOML); with --resume, defaults to the one the
        /// run was started with.
        #[arg(required_unless_present = "resume")]
        scenario: Option<PathBuf>,
        /// Output directory (default: `./out/<scenario stem>`).
        #[arg(
            long,
            conflicts_with = "resume",
            help = "Output directory [default: ./out/<scenario stem>]"
        )]
        out: Option<PathBuf>,
        /// Continue the run in DIR from its checkpoint.
        #[arg(long, value_name = "DIR")]
        resume: Option<PathBuf>,
        /// Print nothing but errors.
        #[arg(long, short, conflicts_with = "verbose")]
        quiet: bool,
        /// Print a line for every step (not only a progress bar).
        #[arg(long, short)]
        verbose: bool,
        /// While one step runs longer than SECONDS (a finer level's
        /// settle is one step, of up to an hour on a fine mesh), print
        /// every SECONDS what it has done: Newton iterations and solves,
        /// the residual, relaxed pseudo-steps, the friction round. 0: never.
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 30.0,
            allow_negative_numbers = true
        )]
        progress_every: f64,
    },
    /// Validate a scenario and summarise it (mesh, loads, schedule) without running it.
    Check {
        /// The scenario file (TOML).
        scenario: PathBuf,
    },
    /// Render the fabric of an output directory: a PNG of one frame, a grid
    /// of frames with a shared colour scale, or a GIF of the whole run.
    ///
    /// Filled triangles coloured by a field (default: vertical displacement),
    /// depth-tested, anti-aliased, with a colour bar; the obstacles of
    /// DIR/scenario.toml in grey.
    Render(RenderArgs),
    /// Plot the history of an output directory: monitors' z, energies,
    /// Newton iterations, contact force, wrinkling states, smallest gap.
    Plot {
        /// The output directory of a run.
        dir: PathBuf,
        /// Output PNG [default: DIR/plot.png].
        #[arg(short = 'o', long)]
        output: Option<PathBuf>,
        /// Image size WxH [default: 1200x900]; 320 to 10000 by 240 to 10000.
        #[arg(long, value_name = "WxH", value_parser = parse_size)]
        size: Option<(u32, u32)>,
    },
    /// Measure a drape as a drape tester does (ISO 9073-9): the shadow's
    /// area, the drape coefficient and the folds of one frame, as one JSON
    /// object on standard output.
    ///
    /// The pedestal (a cylinder obstacle) and the specimen (a disc mesh)
    /// are found in DIR/scenario.toml, or given; the vertical is opposite
    /// the scenario's weight (+z without one).
    Measure {
        /// The output directory of a run (or its fields.pvd).
        dir: PathBuf,
        /// The frame of this step; -1 is the last [default: the last].
        #[arg(long, conflicts_with = "time", allow_negative_numbers = true, value_name = "STEP", value_parser = parse_step)]
        step: Option<FrameSelect>,
        /// The frame nearest this time (s).
        #[arg(long, allow_negative_numbers = true)]
        time: Option<f64>,
        /// The pedestal's radius r_p (m), instead of the scenario's cylinder.
        #[arg(long, value_name = "R", allow_negative_numbers = true)]
        pedestal_radius: Option<f64>,
        /// The specimen's radius R (m), instead of the scenario's disc.
        #[arg(long, value_name = "R", allow_negative_numbers = true)]
        specimen_radius: Option<f64>,
    },
    /// A drape test: N specimens of one scenario, differing by a seeded
    /// perturbation (waviness, the cut's angle to the warp, face up or down),
    /// run side by side; their drape coefficients and folds with the mean,
    /// sd, 95 % interval and fold-count histogram in DIR/test.json, their
    /// shadows in DIR/test.png.
    ///
    /// Each specimen is an ordinary run directory, DIR/specimens/NNNN/.
    /// Running the same command again completes what is missing. Exit
    /// codes: 0 every specimen completed, 1 some did not (test.json says
    /// why), 2 bad input, 130 interrupted.
    Test(drape_test::TestArgs),
    /// List the bundled example scenarios, or print or write one.
    Example {
        /// Example name (as listed); without it, list them.
        name: Option<String>,
        /// Write the example to this file instead of printing it (a new
        /// file: an existing one is refused unless --force).
        #[arg(long)]
        write: Option<PathBuf>,
        /// With --write, replace the file if it exists.
        #[arg(long, requires = "write")]
        force: bool,
    },
}

/// An input error (exit 2), a run failure (exit 1) or an interruption
/// (128 + the signal: 130, 143 or 129).
enum Failure {
    Input(anyhow::Error),
    Run(anyhow::Error),
    Interrupted(anyhow::Error),
}

impl From<ScenarioError> for Failure {
    fn from(e: ScenarioError) -> Self {
        Failure::Input(e.into())
    }
}

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so printing into a closed pipe panics; a command
    // line tool should just stop, as `cat` does.
    #[cfg(unix)]
    // SAFETY: restoring a signal's default disposition before any thread
    // starts has no other effect.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // The main thread runs the simulation; as a worker of rayon's pool its
    // parallel sections (the loops of meshes of 4,096 elements or more,
    // the multigrid) fork locally, where from outside the pool every fork
    // would be handed to the pool and the main thread put to sleep until
    // it is done (two thread wake-ups per fork). Failure (a pool built
    // already) leaves the default pool.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scenario,
            out,
            resume,
            quiet,
            verbose,
            progress_every,
        } => run(scenario, out, resume, quiet, verbose, progress_every),
        Command::Check { scenario } => check(&scenario),
        Command::Render(args) => render(args),
        Command::Plot { dir, output, size } => plot(&dir, output, size),
        Command::Measure {
            dir,
            step,
            time,
            pedestal_radius,
            specimen_radius,
        } => measure::run(&measure::MeasureArgs {
            dir,
            frame: frame(step, time),
            given: drape::measure::Given {
                pedestal_radius,
                specimen_radius,
            },
        })
        .map_err(Failure::Input),
        Command::Test(args) => drape_test::run(args),
        Command::Example { name, write, force } => {
            example(name.as_deref(), write.as_deref(), force)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
        Err(Failure::Interrupted(e)) => {
            // The shell's code of the signal that stopped the run.
            let (signal, name) = signals::received();
            eprintln!("{name}: {e:#}");
            ExitCode::from(signals::exit_code(signal))
        }
    }
}

/// What `drape check` says of the fabric's bending, in SI (what a lab
/// table turned into): its rigidity, its gravity bending length and its
/// hysteresis; `None` without bending.
fn bending_line(m: &drape::model::Model) -> Option<String> {
    use drape::bending::BendingRigidity;
    use drape::bending::hysteresis::Hold;
    let rigidity = match m.bending()?.rigidity {
        BendingRigidity::Isotropic(b) => format!("B = {b:.4e} N m"),
        BendingRigidity::Woven { warp, weft, .. } => {
            format!("B = {warp:.4e} N m warp, {weft:.4e} N m weft")
        }
        BendingRigidity::Plate {
            rigidity,
            poisson_ratio,
        } => format!(
            "plate, D = {} N m, nu = {}",
            human(rigidity),
            human(poisson_ratio)
        ),
    };
    let length = m
        .bending_length()
        .map(|l| format!(", gravity bending length {:.3} cm", 100.0 * l))
        .unwrap_or_default();
    let hysteresis = m
        .bending_hysteresis()
        .map(|h| {
            let [warp, weft] = h.moment;
            let moment = if warp == weft {
                format!("{warp:.4e} N m/m")
            } else {
                format!("{warp:.4e} N m/m warp, {weft:.4e} N m/m weft")
            };
            let hold = match h.hold {
                Hold::Creep { rate } => format!("creeping below {} 1/(m s)", human(rate)),
                Hold::Stick { stiffness } => format!(
                    "held by a stick of {stiffness:.4e} N m (slips past {:.4} 1/m)",
                    h.smoothing(0.0) / h.moment[0].max(h.moment[1])
                ),
            };
            format!("; hysteresis HB = {moment}, {hold}")
        })
        .unwrap_or_default();
    Some(format!("{rigidity}{length}{hysteresis}"))
}

/// The scenario at `path` built, with its text.
fn load(path: &Path) -> Result<(Setup, String), Failure> {
    let (setup, source, _) = load_scenario(path)?;
    Ok((setup, source))
}

/// [`load`], and the scenario itself (what the levels of a `[refine]`
/// run are built from).
fn load_scenario(path: &Path) -> Result<(Setup, String, Scenario), Failure> {
    let (scenario, source) = Scenario::read(path)?;
    Ok((scenario.build(path, &source)?, source, scenario))
}

fn check(path: &Path) -> Result<(), Failure> {
    let (setup, text) = load(path)?;
    let m = &setup.model;
    println!("{}: ok", path.display());
    println!("  title     {}", setup.title);
    let pieces = m.mesh().pieces().1;
    println!(
        "  mesh      {} nodes, {} triangles of order {}, {} DOF ({} fixed), {pieces} {}",
        m.mesh().node_count(),
        m.mesh().element_count(),
        m.mesh().order.degree(),
        m.dofs(),
        m.fixed_count(),
        if pieces == 1 { "piece" } else { "pieces" }
    );
    let mass_kind = match m.mass_kind() {
        drape::model::MassKind::Consistent => "consistent",
        drape::model::MassKind::Lumped => "lumped",
    };
    println!("  mass      {:.6e} kg ({mass_kind})", m.total_mass());
    println!("  loads     {}", m.loads().len());
    if let Some(line) = bending_line(m) {
        println!("  bending   {line}");
    }
    let x = m.initial_positions();
    for (i, cavity) in m.cavities().iter().enumerate() {
        let gas = cavity.initial_state(&x);
        let law = match cavity.gas.law {
            drape::load::gas::GasLaw::Isothermal => "isothermal",
            drape::load::gas::GasLaw::Adiabatic => "adiabatic",
        };
        let mut flows = Vec::new();
        if cavity.gas.inflator.is_some() {
            flows.push("an inflator".to_string());
        }
        match cavity.gas.vents.len() {
            0 => {}
            1 => flows.push("a vent".into()),
            n => flows.push(format!("{n} vents")),
        }
        let flows = if flows.is_empty() {
            String::new()
        } else {
            format!(", {}", flows.join(" and "))
        };
        println!(
            "  cavity {i}  {} triangles enclosing {:.6e} m^3, {law} gas: {:.6e} kg at {:.1} Pa, {:.2} K{flows}",
            cavity.surface.elements().len(),
            gas.volume,
            gas.mass,
            gas.pressure,
            gas.temperature
        );
    }
    if let Some(f) = m.obstacle_features() {
        println!(
            "  features  {} points of the obstacles' corners, edges and rims, at most {:.3e} m apart, kept out of {} triangles",
            f.point_count(),
            f.spacing(),
            f.triangles().len()
        );
    }
    if let Some(sc) = m.self_contact() {
        let friction = if sc.friction() > 0.0 {
            format!("friction {} between the layers", human(sc.friction()))
        } else {
            "frictionless".into()
        };
        println!(
            "  self      self-contact on {} triangles, its barrier within {} m, {friction}",
            sc.triangles().len(),
            human(sc.distance())
        );
    }
    match &setup.analysis {
        drape::setup::Analysis::Dynamic { newmark, segments } => {
            let steps: usize = segments.iter().map(|s| s.0).sum();
            let end = setup.analysis.end_time();
            println!(
                "  dynamic   beta = {}, gamma = {}, {steps} {} to t = {} s",
                human(newmark.beta),
                human(newmark.gamma),
                if steps == 1 { "step" } else { "steps" },
                human(end)
            );
            if let Some(adaptive) = &setup.adaptive {
                let dt_max = match adaptive.dt_max {
                    Some(dt_max) => format!("{} s", human(dt_max)),
                    None => "10 x each segment's dt".into(),
                };
                println!("  adaptive  steps grow after easy steps up to dt_max = {dt_max}");
            }
            if let Some(rest) = &setup.rest {
                println!(
                    "  rest      ends once every node is slower than {:e} m/s for {} steps, from t = {} s",
                    rest.speed,
                    drape::simulation::schedule::REST_STEPS,
                    human(rest.after)
                );
            }
        }
        drape::setup::Analysis::Static { steps, .. } => {
            println!(
                "  static    {steps} load {}",
                if *steps == 1 {
                    "increment"
                } else {
                    "increments"
                }
            )
        }
    }
    if let Some(r) = &setup.refine {
        let region = if r.uniform {
            "every triangle".to_string()
        } else {
            let measure = if r.chord {
                "the curvature times the area (the sag)"
            } else {
                "the curvature"
            };
            let also = match (r.rim, r.contact_line) {
                (true, true) => ", and the rim and the contact line",
                (true, false) => ", and the rim",
                (false, true) => ", and the contact line",
                (false, false) => "",
            };
            format!(
                "along the folds (the triangles holding {} of {measure}){also}",
                r.fraction
            )
        };
        println!(
            "  refine    up to {} {}, {region}, each finer level settled statically; stop when the drape coefficient changes by less than {}",
            r.levels,
            if r.levels == 1 { "level" } else { "levels" },
            r.tolerance
        );
    }
    for warning in simulation::warnings(&setup) {
        println!("  warning   {warning}");
    }
    if let Ok(scenario) = Scenario::parse(&text, path) {
        print_specimen(&scenario);
    }
    for mon in &setup.monitors {
        println!(
            "  monitor   {} -> node {} at {:?}",
            mon.name,
            mon.node,
            m.mesh().nodes[mon.node]
        );
    }
    Ok(())
}

/// `drape check`'s lines of a drape test's `[test]` and `[specimen]`.
fn print_specimen(s: &Scenario) {
    if let Some(t) = &s.test {
        let faces = match t.faces {
            drape::scenario::Faces::Both => "alternately face up and down",
            drape::scenario::Faces::Up => "all face up",
        };
        println!(
            "  test      drape test specimens: waviness {} m ({} modes), cuts within ±{}°, {faces}",
            human(t.waviness),
            t.waviness_modes,
            human(t.cut_angle)
        );
    }
    if let Some(p) = &s.specimen {
        println!(
            "  specimen  waviness {} m (seed {}, {} modes), cut at {:.3}° to the warp, face {}",
            human(p.waviness),
            p.seed,
            p.waviness_modes,
            p.cut_angle,
            p.face.name()
        );
    }
}

fn run(
    scenario: Option<PathBuf>,
    out: Option<PathBuf>,
    resume: Option<PathBuf>,
    quiet: bool,
    verbose: bool,
    progress_every: f64,
) -> Result<(), Failure> {
    if !(progress_every.is_finite() && progress_every >= 0.0) {
        return Err(Failure::Input(anyhow::anyhow!(
            "--progress-every {progress_every}: a number of seconds, 0 or more, is needed"
        )));
    }
    // Ctrl-C or SIGTERM while the scenario is read and built (a large
    // mesh takes seconds) ends the process at once, saying so.
    signals::install();
    let directory_error = |e: DirectoryError| Failure::Input(e.into());
    // A resume holds its directory before it reads anything, so that a
    // refusal can be recorded in the summary without racing another writer.
    let resumed = match &resume {
        Some(dir) => Some(Session::resume(dir, Front::CommandLine).map_err(directory_error)?),
        None => None,
    };
    let (path, (setup, text, parsed)) = match (&scenario, &resumed) {
        (Some(p), None) => (p.clone(), load_scenario(p)?),
        (_, Some(session)) => load_to_resume(scenario.clone(), session)?,
        (None, None) => unreachable!("clap requires one of them"),
    };
    // From here on (the directory is about to be written) a signal no
    // longer ends the process at once: it asks the run to stop after its
    // current step (checkpoint, summary).
    signals::setup_done();
    let path = path.as_path();
    // One writer per directory, held to the end of the run; a fresh run
    // starts from a directory of drape's own with its old outputs gone.
    let session = match resumed {
        Some(session) => session,
        None => {
            let out = out.unwrap_or_else(|| {
                let stem = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "run".into());
                PathBuf::from("out").join(stem)
            });
            let session = Session::fresh(&out, Front::CommandLine).map_err(directory_error)?;
            session.start_fresh(Some(path)).map_err(directory_error)?;
            session
                .keep_scenario(Some(path), &text, &setup)
                .map_err(|message| Failure::Run(anyhow::anyhow!(message)))?;
            session
        }
    };
    let out = session.dir();
    let start = Instant::now();
    let mut progress = Progress::new(quiet, verbose, setup.adaptive.is_some());
    for warning in simulation::warnings(&setup) {
        eprintln!("warning: {warning}");
    }
    let counts = Arc::new(StepProgress::new());
    let mut control = session.control(Some(&signals::STOP));
    control.progress = Some(&counts);
    let watching = (!quiet && progress_every > 0.0).then(|| {
        watch_long_steps(
            counts.clone(),
            Duration::from_secs_f64(progress_every),
            progress.bar.clone(),
        )
    });
    let result = drape::levels::run_with(
        &parsed,
        (path, &text),
        &setup,
        out,
        &mut |info| progress.step(info),
        control,
    );
    if let Some((stop, watcher)) = watching {
        stop.store(true, Ordering::Relaxed);
        let _ = watcher.join();
    }
    if let Some(bar) = &progress.bar {
        bar.finish_and_clear();
    }
    match result {
        Ok(summary) => {
            if !quiet {
                print_completed(&summary, start, out);
            }
            Ok(())
        }
        Err(e) => Err(match e.cause() {
            RunError::Interrupted { .. } => Failure::Interrupted(anyhow::Error::new(e)),
            RunError::Resume { .. } => Failure::Input(anyhow::Error::new(e)),
            RunError::Io { .. } => Failure::Run(anyhow::Error::new(e)),
            _ => Failure::Run(
                anyhow::Error::new(e).context(format!("run of {} failed", path.display())),
            ),
        }),
    }
}

/// The scenario a resume of the session's directory goes on with
/// (`scenario`, or the one the run started with), its setup and its text;
/// a refusal is recorded in the directory's summary.
fn load_to_resume(
    scenario: Option<PathBuf>,
    session: &Session,
) -> Result<(PathBuf, (Setup, String, Scenario)), Failure> {
    let path = match scenario {
        Some(p) => p,
        None => session.started_with().map_err(|e| {
            record_refusal(
                session,
                Failure::Input(anyhow::anyhow!(
                    "{}: {e}; is {} the output directory of a drape run? (or name the scenario: drape run SCENARIO --resume DIR)",
                    session.dir().join(directory::SCENARIO_PATH).display(),
                    session.dir().display()
                )),
            )
        })?,
    };
    // A changed or missing input file is named as such, before the
    // scenario reads it (its refusal recorded).
    session
        .check_inputs()
        .map_err(|message| Failure::Input(anyhow::anyhow!(message)))?;
    let loaded = load_scenario(&path).map_err(|failure| record_refusal(session, failure))?;
    Ok((path, loaded))
}

/// What a run shows of its progress: a bar on a terminal (with each
/// step's line when `verbose`), else a line a second (each step's when
/// `verbose`), nothing when `quiet`.
struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    verbose: bool,
    /// Progress in simulated time rather than in scheduled steps.
    adaptive: bool,
    last_print: Instant,
}

impl Progress {
    fn new(quiet: bool, verbose: bool, adaptive: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        // Progress in scheduled steps: they, not simulated time, cost the
        // wall time; adaptive steps are not known in advance, so there it is
        // simulated time, in thousandths of the schedule.
        let bar = (terminal && !quiet).then(|| {
            let bar = ProgressBar::new(1000);
            let template = if adaptive {
                "{bar:30.cyan/blue} {percent}% of the time, t = {msg} [{elapsed_precise} elapsed, {eta} left]"
            } else {
                "{bar:30.cyan/blue} {pos}/{len} steps, t = {msg} [{elapsed_precise} elapsed, {eta} left]"
            };
            bar.set_style(
                ProgressStyle::with_template(template)
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar
        });
        Self {
            bar,
            quiet,
            verbose,
            adaptive,
            last_print: Instant::now(),
        }
    }

    /// After each converged step.
    fn step(&mut self, info: &StepInfo) {
        if self.quiet {
            return;
        }
        let cut_back = |separator: &str| {
            if info.cutbacks > 0 {
                format!("{separator}cut back x{}", info.cutbacks)
            } else {
                String::new()
            }
        };
        let line = format!(
            "step {:>6}  t = {:.5e} / {:.4e} s  dt = {:.2e}  Newton {:>2}{}  KE {:.3e} J  SE {:.3e} J",
            info.step,
            info.time,
            info.end_time,
            info.dt,
            info.iterations,
            if info.cutbacks > 0 {
                format!("  ({})", cut_back(""))
            } else {
                String::new()
            },
            info.kinetic_energy,
            info.strain_energy
        );
        if let Some(bar) = &self.bar {
            if self.adaptive {
                let fraction = (info.time / info.end_time).clamp(0.0, 1.0);
                bar.set_position((1000.0 * fraction) as u64);
            } else {
                bar.set_length(info.scheduled_total as u64);
                bar.set_position(info.scheduled_done as u64);
            }
            bar.set_message(format!(
                "{:.4e} s, step {}, Newton {}{}",
                info.time,
                info.step,
                info.iterations,
                cut_back(", ")
            ));
            if self.verbose {
                bar.println(&line);
            }
        } else if self.verbose
            || self.last_print.elapsed().as_secs_f64() >= 1.0
            || info.time >= info.end_time * (1.0 - 1e-12)
        {
            eprintln!("{line}");
            self.last_print = Instant::now();
        }
    }
}

/// A thread that prints, every `every` while one step has run for longer
/// than `every`, what the step has done ([`step_in_progress`]); stopped
/// by setting the flag it returns.
fn watch_long_steps(
    counts: Arc<StepProgress>,
    every: Duration,
    bar: Option<ProgressBar>,
) -> (Arc<AtomicBool>, std::thread::JoinHandle<()>) {
    let stop = Arc::new(AtomicBool::new(false));
    let stopped = stop.clone();
    let watcher = std::thread::spawn(move || {
        let poll = every.min(Duration::from_millis(200));
        let (mut steps, mut since, mut printed) = (counts.read().steps, Instant::now(), None);
        while !stopped.load(Ordering::Relaxed) {
            std::thread::sleep(poll);
            let reading = counts.read();
            if reading.steps != steps {
                (steps, since, printed) = (reading.steps, Instant::now(), None);
                continue;
            }
            // Between a level's step and the next level's first solve
            // (measured, refined, built) nothing is solving.
            let due = printed.is_none_or(|at: Instant| at.elapsed() >= every);
            if since.elapsed() >= every && due && reading.solves > 0 {
                let line = step_in_progress(&reading, since.elapsed());
                match &bar {
                    Some(bar) => bar.println(&line),
                    None => eprintln!("{line}"),
                }
                printed = Some(Instant::now());
            }
        }
    });
    (stop, watcher)
}

/// The line on a step that has run for `running`: its number, the level
/// of a multilevel settle, Newton's iterations and solves with the last
/// residual, the relaxed increment's pseudo-steps and the friction round.
fn step_in_progress(r: &ProgressReading, running: Duration) -> String {
    let seconds = running.as_secs();
    let mut line = format!(
        "step {} running for {}:{:02}",
        r.steps + 1,
        seconds / 60,
        seconds % 60
    );
    if r.level > 0 {
        line += &format!(", level {} ({} T3)", r.level, r.elements);
    }
    line += &format!(
        ": {} Newton {} in {} {}",
        r.iterations,
        if r.iterations == 1 {
            "iteration"
        } else {
            "iterations"
        },
        r.solves,
        if r.solves == 1 { "solve" } else { "solves" }
    );
    if r.residual.is_finite() {
        line += &format!(", residual {:.3e} N", r.residual);
    }
    if r.pseudo_steps > 0 {
        line += &format!(", relaxed: pseudo-step {}", r.pseudo_steps);
    }
    if r.friction_round > 0 {
        line += &format!(", friction round {}", r.friction_round);
    }
    line
}

/// What a completed run prints: rest, steps, energy balance, monitors.
fn print_completed(summary: &simulation::Summary, start: Instant, out: &Path) {
    if summary.at_rest == Some(true) {
        println!("{}", summary.message);
    }
    let discarded = match summary.newton_iterations_discarded {
        0 => String::new(),
        n => format!(" and {n} in solves thrown away"),
    };
    println!(
        "completed {} {} to t = {:.6} s in {:.2} s ({} Newton iterations{discarded}, {} cut-back steps)",
        summary.steps,
        if summary.steps == 1 { "step" } else { "steps" },
        summary.time,
        start.elapsed().as_secs_f64(),
        summary.newton_iterations,
        summary.cutbacks
    );
    println!(
        "energy: kinetic {:.6e} J + strain {:.6e} J - work of loads {:.6e} J = {:.6e} J",
        summary.kinetic_energy,
        summary.strain_energy,
        summary.external_work,
        summary.kinetic_energy + summary.strain_energy - summary.external_work
    );
    for (name, p) in &summary.monitors {
        println!("monitor {name}: [{:.6}, {:.6}, {:.6}]", p[0], p[1], p[2]);
    }
    println!("results in {}", out.display());
}

/// A resume refused after its directory was locked: the refusal goes into
/// the directory's summary (status "failed", its counts kept; a completed
/// run's summary is left alone), and is returned.
fn record_refusal(session: &Session, failure: Failure) -> Failure {
    let (Failure::Input(e) | Failure::Run(e) | Failure::Interrupted(e)) = &failure;
    match session.refuse(&format!("{e:#}")) {
        Ok(_) => failure,
        Err(unrecorded) => Failure::Input(anyhow::anyhow!(unrecorded)),
    }
}

// `drape render`'s arguments (the subcommand's and the function's).
#[derive(clap::Args)]
struct RenderArgs {
    /// The output directory of a run (or its fields.pvd).
    dir: PathBuf,
    /// The frame of this step; -1 is the last [default: the last].
    #[arg(long, conflicts_with = "time", allow_negative_numbers = true, value_name = "STEP", value_parser = parse_step)]
    step: Option<FrameSelect>,
    /// The frame nearest this time (s).
    #[arg(long, allow_negative_numbers = true)]
    time: Option<f64>,
    /// Camera.
    #[arg(long, value_enum, default_value_t = View::Perspective)]
    view: View,
    /// The field that colours the fabric.
    #[arg(long, value_enum, default_value_t = Field::DisplacementZ)]
    field: Field,
    /// A panel of frames from the first to the last, one colour scale.
    #[arg(long, conflicts_with_all = ["animate", "step", "time"])]
    grid: bool,
    /// Panels of --grid.
    #[arg(long, default_value_t = 6, allow_negative_numbers = true)]
    panels: usize,
    /// Every written frame into a GIF.
    #[arg(long)]
    animate: bool,
    /// Delay between animation frames (ms).
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    delay_ms: u32,
    /// Output file [default: DIR/render.png, DIR/render-grid.png or DIR/animation.gif].
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
    /// Draw the obstacles of this scenario [default: DIR/scenario.toml].
    #[arg(long)]
    scenario: Option<PathBuf>,
    /// Do not draw obstacles.
    #[arg(long)]
    no_obstacles: bool,
    /// Image size WxH [default: 1200x900; 800x600 with --animate]; 160 to
    /// 10000 by 120 to 10000, and at most 2 GiB of pixel buffers (3x
    /// supersampled: about 5000x5000).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Colour scale limits instead of the field's range.
    #[arg(long, num_args = 2, value_names = ["MIN", "MAX"], allow_negative_numbers = true)]
    range: Option<Vec<f64>>,
}

/// `--step N` of render and measure: the frame of step N, or with -1 the
/// last frame written (as `positions(step=-1)` in Python); the frame's
/// existence is checked against the run's frames.
fn parse_step(text: &str) -> Result<FrameSelect, String> {
    match text.trim().parse::<i64>() {
        Ok(-1) => Ok(FrameSelect::Last),
        Ok(step) => u64::try_from(step).map(FrameSelect::Step).map_err(|_| {
            format!("{step} is not a step: a step number (>= 0), or -1 for the last frame written")
        }),
        Err(_) => Err("expected a step number (>= 0), or -1 for the last frame written".into()),
    }
}

/// The frame `--step` or `--time` picks (clap lets one of them through),
/// else the last.
fn frame(step: Option<FrameSelect>, time: Option<f64>) -> FrameSelect {
    match (step, time) {
        (Some(step), _) => step,
        (_, Some(t)) => FrameSelect::Time(t),
        _ => FrameSelect::Last,
    }
}

/// `--size WxH` in pixels; the renderer checks the range (render and plot
/// have their own) and the memory it needs.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    text.split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)))
        .ok_or_else(|| "expected WxH in pixels, e.g. 1200x900".to_string())
}

fn render(a: RenderArgs) -> Result<(), Failure> {
    use drape_render::{Layout, RenderOptions};
    let input = |e: drape_render::RenderError| Failure::Input(anyhow::Error::new(e));
    let (width, height) = (a.size).unwrap_or(if a.animate { (800, 600) } else { (1200, 900) });
    let mut opts = RenderOptions {
        layout: if a.animate {
            Layout::Animation {
                frame_delay_ms: a.delay_ms,
            }
        } else if a.grid {
            Layout::Grid { panels: a.panels }
        } else {
            Layout::Single
        },
        frame: frame(a.step, a.time),
        view: a.view,
        field: a.field,
        width,
        height,
        output: a.output,
        scenario: a.scenario,
        obstacles: !a.no_obstacles,
        range: a.range.map(|r| (r[0], r[1])),
        ..Default::default()
    };
    // A drape tester seen from above: the pedestal and the specimen's
    // circle over the fabric, the measurement in the subtitle.
    if a.view == View::Top
        && opts.layout == Layout::Single
        && !a.no_obstacles
        && let Some((circles, caption)) = measure::top_view_overlay(&a.dir, opts.frame)
    {
        opts.circles = circles;
        opts.caption = Some(caption);
    }
    let report = drape_render::render(&a.dir, &opts).map_err(input)?;
    for n in &report.notices {
        eprintln!("note: {n}");
    }
    if let Some(out) = report.output {
        println!("wrote {}", out.display());
    }
    Ok(())
}

fn plot(dir: &Path, output: Option<PathBuf>, size: Option<(u32, u32)>) -> Result<(), Failure> {
    // A drape-tester run: its drape coefficient and folds frame by frame too.
    let extra = measure::drape_panels(dir).unwrap_or_default();
    let rows = if extra.is_empty() { 900 } else { 1200 };
    let (width, height) = size.unwrap_or((1200, rows));
    let out = output.unwrap_or_else(|| dir.join("plot.png"));
    drape_render::plot_with(dir, &out, width, height, &extra)
        .map_err(|e| Failure::Input(anyhow::Error::new(e)))?;
    println!("wrote {}", out.display());
    Ok(())
}

fn example(name: Option<&str>, write: Option<&Path>, force: bool) -> Result<(), Failure> {
    let Some(name) = name else {
        println!("bundled examples (drape example NAME [--write FILE]):");
        for (n, text) in examples::ALL {
            let title = text
                .lines()
                .find_map(|l| l.strip_prefix("title = "))
                .map(|t| t.trim().trim_matches('"'))
                .unwrap_or("");
            println!("  {n:<28} {title}");
        }
        return Ok(());
    };
    let name = name.trim_end_matches(".toml");
    let text = examples::ALL
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let names: Vec<&str> = examples::ALL.iter().map(|(n, _)| *n).collect();
            Failure::Input(anyhow::anyhow!(
                "no example named {name:?}; the examples are: {}",
                names.join(", ")
            ))
        })?;
    let Some(path) = write else {
        print!("{text}");
        for (file, _) in examples::files_of(name) {
            eprintln!(
                "note: example {name:?} reads {file} beside it; `drape example {name} --write FILE` writes both"
            );
        }
        return Ok(());
    };
    // A bad target is the user's input (exit 2): a directory, or a file
    // that exists (a scenario of one's own) unless --force.
    if path.is_dir() {
        return Err(Failure::Input(anyhow::anyhow!(
            "cannot write example {name:?} to {}: it is a directory; give a file name",
            path.display()
        )));
    }
    let mut options = std::fs::OpenOptions::new();
    options.write(true);
    if force {
        options.create(true).truncate(true);
    } else {
        options.create_new(true);
    }
    let mut file = match options.open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            return Err(Failure::Input(anyhow::anyhow!(
                "cannot write example {name:?} to {}: the file exists (add --force to replace it)",
                path.display()
            )));
        }
        Err(e) => {
            return Err(Failure::Input(
                anyhow::Error::new(e).context(format!("cannot write {}", path.display())),
            ));
        }
    };
    use std::io::Write;
    file.write_all(text.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))
        .map_err(Failure::Run)?;
    // The files it reads, beside it (an identical one already there is
    // left as it is; another is replaced only with --force).
    let dir = path.parent().unwrap_or(Path::new("."));
    for (file, bytes) in examples::files_of(name) {
        let target = dir.join(file);
        if let Ok(existing) = std::fs::read(&target) {
            if existing == bytes {
                continue;
            }
            if !force {
                return Err(Failure::Input(anyhow::anyhow!(
                    "cannot write {}, which example {name:?} reads: the file exists and differs (add --force to replace it)",
                    target.display()
                )));
            }
        }
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("cannot make {}", parent.display()))
                .map_err(Failure::Run)?;
        }
        std::fs::write(&target, bytes)
            .with_context(|| format!("cannot write {}", target.display()))
            .map_err(Failure::Run)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line on a long step: a relaxed finer level in its third
    /// friction round, and a plain step of a single-level run.
    #[test]
    fn a_step_in_progress_is_said_in_one_line() {
        let relaxed = ProgressReading {
            steps: 41,
            iterations: 1234,
            solves: 57,
            residual: 2.5e-3,
            pseudo_steps: 45,
            friction_round: 3,
            level: 3,
            elements: 12540,
        };
        assert_eq!(
            step_in_progress(&relaxed, Duration::from_secs(754)),
            "step 42 running for 12:34, level 3 (12540 T3): 1234 Newton iterations in 57 solves, \
             residual 2.500e-3 N, relaxed: pseudo-step 45, friction round 3"
        );
        let plain = ProgressReading {
            iterations: 1,
            solves: 1,
            residual: f64::NAN,
            ..ProgressReading::default()
        };
        assert_eq!(
            step_in_progress(&plain, Duration::from_secs(31)),
            "step 1 running for 0:31: 1 Newton iteration in 1 solve"
        );
    }
}
