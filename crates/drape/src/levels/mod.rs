//! The multilevel settle (`[refine]`, SPEC §6.7): decide the folds on a
//! coarse mesh, refine where they are, finish each finer level statically
//! from the coarser level's shape.
//!
//! Level 0 is the scenario as written (a dynamic fall to rest, or its
//! static increments). Then, up to `[refine] levels` times: the level's
//! last state is measured (the drape coefficient and the folds, where the
//! scenario has a drape tester: [`crate::measure`]); its mesh is split —
//! every triangle (`where = "all"`), or those that hold `fraction` of the
//! curvature indicator ([`indicator`]), closed green so that no node
//! hangs, the green splits of the level before undone where the split
//! reaches them so that no triangle is halved twice
//! ([`crate::mesh::refine`]) —; the state is carried onto the new
//! mesh with its new nodes on the surface, or on their chords where the
//! surface would compress an element past Saint-Venant–Kirchhoff's
//! stability ([`transfer`]); the scenario is built again on the new
//! mesh, by the one path every term follows ([`Scenario::build_level`]:
//! supports, loads, monitors, mass, bending patches, contact and the
//! Hessian's layout all made from the mesh), as a static analysis of one
//! load increment at the full load; and that level is settled. The run
//! stops refining when the drape coefficient changes by less than
//! `tolerance` between two levels — with `resolution` set, only on a
//! mesh that resolves the fabric's gravity bending length ([`resolved`]).
//!
//! One output directory holds every level: the history goes on (its
//! `elements` column says which mesh each row is on; a finer level's time
//! is the coarser level's end plus its load factor, so that time rises),
//! the frames go on in the same collection, each on its own mesh, and
//! `summary.json` lists the levels. A checkpoint records the refinements
//! (the elements each split marked), so that a resume builds the same
//! meshes again and goes on bit for bit.

pub mod indicator;
pub mod transfer;

use crate::integrator::State;
use crate::material::CRITICAL_STRETCH;
use crate::measure::{DrapeTester, Given, Surface, measure};
use crate::model::Model;
use crate::scenario::Scenario;
use crate::setup::{Analysis, Setup};
use crate::simulation::{
    self, Checkpoint, LevelRecord, LevelStart, Levels, RunControl, RunError, StepInfo, Summary,
    checkpoint_path,
};
use std::path::Path;
use std::time::Instant;
pub use transfer::{Transfer, TransferError};

/// Runs `setup`, built from `scenario` (read from `file`, whose text is
/// `source`), into `out`: as [`simulation::run_with`] does, and level by
/// level where the scenario has `[refine]` (module docs).
///
/// # Errors
/// Those of [`simulation::run_with`]; a level that cannot be built or
/// refined is [`RunError::Refine`], recorded in the summary.
pub fn run_with(
    scenario: &Scenario,
    (file, source): (&Path, &str),
    setup: &Setup,
    out: &Path,
    observer: &mut dyn FnMut(&StepInfo),
    control: RunControl,
) -> Result<Summary, RunError> {
    let Some(plan) = setup.refine else {
        return simulation::run_with(setup, out, observer, control);
    };
    // A resume replays the refinements its checkpoint recorded; one that
    // cannot be read is refused by the session, on the coarse setup.
    let mut levels = if control.resume {
        std::fs::read(checkpoint_path(out))
            .ok()
            .and_then(|bytes| Checkpoint::recorded_levels(&bytes).ok())
            .unwrap_or_default()
    } else {
        Levels::default()
    };
    let coarse = setup.model.mesh();
    let tester = DrapeTester::find(Some(scenario), coarse, 0.0, Given::default());
    let mut mesh = coarse.clone();
    // The green splits of the refinement that made the current level: the
    // next one undoes them where it reaches them.
    let mut greens = Vec::new();
    for (k, marks) in levels.marks.iter().enumerate() {
        let flags = flags_of(marks, mesh.element_count());
        let refinement = Transfer::new(&mesh, &flags, &greens)
            .map_err(|e| refine_error(out, k + 1, e.to_string()))?
            .refinement;
        (mesh, greens) = (refinement.mesh, refinement.greens);
    }
    let mut level: Option<Setup> = match levels.marks.len() {
        0 => None,
        k => {
            let from = levels.records.get(k - 1).map_or(0.0, |r| r.time);
            Some(build_level(
                scenario,
                (file, source),
                setup,
                mesh,
                from,
                out,
                k,
            )?)
        }
    };
    let mut start: Option<LevelStart> = None;
    let mut resume = control.resume;
    loop {
        let current = level.as_ref().unwrap_or(setup);
        if let Some(p) = control.progress {
            p.level(levels.marks.len(), current.model.mesh().element_count());
        }
        let session = RunControl { resume, ..control };
        let finished = simulation::run_level(
            current,
            out,
            observer,
            session,
            start.take(),
            (&levels, true),
        )?;
        resume = false;
        let since = Instant::now();
        let k = levels.marks.len();
        let model = &current.model;
        // The level's share of the run's counts: what the levels before
        // it did not (a resumed level's session started mid-level).
        let done = |f: fn(&LevelRecord) -> usize| levels.records.iter().map(f).sum::<usize>();
        let seconds: f64 = levels.records.iter().map(|r| r.wall_seconds).sum();
        let mut record = LevelRecord {
            elements: model.mesh().element_count(),
            nodes: model.mesh().node_count(),
            steps: finished.counters.step - done(|r| r.steps),
            newton_iterations: finished.counters.iterations - done(|r| r.newton_iterations),
            wall_seconds: (finished.counters.wall_seconds - seconds).max(0.0),
            time: finished.state.time,
            ..LevelRecord::default()
        };
        match &tester {
            Ok(tester) => {
                let positions: Vec<[f64; 3]> = finished
                    .state
                    .positions
                    .chunks(3)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect();
                let surface = Surface {
                    positions: &positions,
                    connectivity: &model.mesh().connectivity,
                    order: model.mesh().order,
                };
                match measure(&surface, tester) {
                    Ok(m) => {
                        record.drape_coefficient = Some(m.drape_coefficient);
                        record.folds = Some(m.folds);
                    }
                    Err(e) => record.note = Some(format!("not measured: {e}")),
                }
            }
            Err(e) => record.note = Some(format!("no drape coefficient: {e}")),
        }
        let change = match (levels.records.last(), record.drape_coefficient) {
            (Some(previous), Some(dc)) => previous.drape_coefficient.map(|p| (dc - p).abs()),
            _ => None,
        };
        record.wall_seconds += since.elapsed().as_secs_f64();
        levels.records.push(record);
        let resolution = resolved(model, plan.resolution);
        let converged = change.is_some_and(|c| c < plan.tolerance) && resolution.is_ok();
        let mut summary = finished.summary;
        summary.levels.clone_from(&levels.records);
        summary.wall_seconds += since.elapsed().as_secs_f64();
        if k == plan.levels || converged {
            summary.message = format!(
                "{}; {}",
                summary.message,
                says(&levels.records, converged, resolution)
            );
            simulation::rewrite_summary(out, &summary)?;
            return Ok(summary);
        }
        // The level's session wrote no summary (the run goes on): one that
        // cannot refine records this one's, failed.
        let failed = |e: RunError| {
            let mut summary = summary.clone();
            summary.status = "failed".into();
            summary.message = e.to_string();
            match simulation::rewrite_summary(out, &summary) {
                Ok(()) => e,
                Err(RunError::Io { error, .. }) => RunError::Unrecorded {
                    cause: Box::new(e),
                    error,
                },
                Err(other) => other,
            }
        };
        // Refine, carry the state over, build the finer level.
        let flags = if plan.uniform {
            vec![true; model.mesh().element_count()]
        } else {
            let mut eta = indicator::curvature_indicator(model.mesh(), &finished.state.positions);
            if plan.chord {
                indicator::times_area(model.mesh(), &mut eta);
            }
            let mut flags = indicator::dorfler(&eta, plan.fraction);
            if plan.rim {
                indicator::mark_rim(model.mesh(), &mut flags);
            }
            if plan.contact_line {
                let touching = touching(model, &finished.state);
                indicator::mark_across(model.mesh(), &touching, &mut flags);
            }
            flags
        };
        let transfer = Transfer::new(model.mesh(), &flags, &greens)
            .map_err(|e| failed(refine_error(out, k + 1, e.to_string())))?;
        greens.clone_from(&transfer.refinement.greens);
        levels
            .marks
            .push((0..flags.len()).filter(|&e| flags[e]).collect());
        let fine = transfer.refinement.mesh.clone();
        let next = build_level(
            scenario,
            (file, source),
            setup,
            fine,
            finished.state.time,
            out,
            k + 1,
        )
        .map_err(failed)?;
        let state = carry(&next, &transfer, (model, &finished.state));
        let mut counters = finished.counters;
        counters.wall_seconds += since.elapsed().as_secs_f64();
        start = Some(LevelStart {
            state,
            counters,
            written: finished.written,
        });
        level = Some(next);
    }
}

/// Whether each node of `model`'s mesh touches an obstacle in `state`:
/// an obstacle's force on it (none without obstacles).
fn touching(model: &crate::model::Model, state: &State) -> Vec<bool> {
    let nodes = model.mesh().node_count();
    match (model.contact(), state.contact.as_ref()) {
        (Some(contact), Some(cs)) => contact
            .report(&state.positions, state.time, cs)
            .nodal_forces
            .iter()
            .map(|f| f.iter().any(|v| *v != 0.0))
            .collect(),
        _ => vec![false; nodes],
    }
}

/// One flag per element of a mesh of `count`, set where `marks` lists it.
fn flags_of(marks: &[usize], count: usize) -> Vec<bool> {
    let mut flags = vec![false; count];
    for &e in marks {
        if let Some(f) = flags.get_mut(e) {
            *f = true;
        }
    }
    flags
}

/// The setup of level `k` on `mesh`: the scenario built on it, static
/// from the time `from`.
fn build_level(
    scenario: &Scenario,
    (file, source): (&Path, &str),
    coarse: &Setup,
    mesh: crate::mesh::Mesh,
    from: f64,
    out: &Path,
    k: usize,
) -> Result<Setup, RunError> {
    let mut setup = scenario
        .build_level(file, source, mesh, coarse.inputs.clone())
        .map_err(|e| refine_error(out, k, e.to_string()))?;
    setup.analysis = Analysis::Static { steps: 1, from };
    setup.refine = coarse.refine;
    // The increment is the level's whole settle.
    setup.newton.max_iterations = setup.newton.max_iterations.max(LEVEL_ITERATIONS);
    Ok(setup)
}

/// The fewest Newton iterations a finer level's increment is given: it
/// settles the level from the carried shape (measured: 41 on the
/// quasi-static 15-ring disc's first level, 171 on the gripped tester's,
/// which stalls at the examples' 30 and fails through 6 halvings). Where
/// even these do not suffice the increment is relaxed in pseudo-time at
/// once, not halved (`integrator::statics`): on the 8-ring disc of the
/// tests the second level failed in 200 from the full load and was
/// relaxed (276 iterations in all; halved instead, it settled from a
/// quarter of the load, in another fold pattern). They now settle at
/// once (86 and 141 iterations; 75 and 33 since `carry` keeps the fine
/// elements from being crushed across the folds); with a membrane ten
/// times stiffer and the weight put on in one increment, the first finer
/// level still fails in 200 and is relaxed (7 pseudo-steps).
pub const LEVEL_ITERATIONS: usize = 200;

/// The state `coarse` (of `coarse_model`) carried onto `fine`'s mesh by
/// `transfer`, at rest (a static level), its time, work and friction
/// dissipation kept, a stick hysteresis's springs loaded as they were
/// ([`crate::integrator::carry_springs`]); a new node held by a support
/// at its reference position. The new nodes go on
/// the surface ([`transfer`]), but not where that compresses a fine
/// element past [`CRITICAL_STRETCH`], where Saint-Venant–Kirchhoff loses
/// stability and which no converged step may keep: across a tight fold
/// of the coarse level the surface's quadratic overshoots, and the new
/// nodes of such elements go back on their chords
/// ([`Transfer::onto_chords`]), where a fine triangle is strained as its
/// coarse one. Measured on Matsudaira B's third specimen on ISO's
/// geometry (docs/validation.md, "A finer level crushed by its start"):
/// the surface alone carried a coarse state whose least principal stretch
/// was 0.996 into one of 0.071 (31 elements below `1/sqrt(3)`), and its
/// fifth level settled into a collapsed element and failed. Putting back
/// every new node of an element more compressed than the coarse state's
/// least (about a third of them there) cost the multilevel benchmark
/// 22 % more Newton iterations on its finer levels (31 % more time) and
/// a faille's third level ten times its iterations: milder compressions
/// are left for the level's settle to undo.
fn carry(fine: &Setup, transfer: &Transfer, (coarse_model, coarse): (&Model, &State)) -> State {
    let model = &fine.model;
    let mut positions = transfer.carry(&coarse.positions);
    transfer.onto_chords(&coarse.positions, &mut positions, |y| {
        model.elements_compressed_below(y, CRITICAL_STRETCH)
    });
    let reference = model.initial_positions();
    for (i, held) in model.fixed().iter().enumerate() {
        if *held && i >= coarse.positions.len() {
            positions[i] = reference[i];
        }
    }
    let mut state = State::at_rest(model, positions);
    state.time = coarse.time;
    state.external_work = coarse.external_work;
    state.friction_dissipation = coarse.friction_dissipation;
    // A stick hysteresis's springs loaded as on the coarse level.
    crate::integrator::carry_springs(
        (coarse_model, coarse),
        model,
        &transfer.refinement.parent,
        &mut state.plastic,
    );
    state
}

/// The mean length of the edges of `mesh` in its reference configuration
/// (m): of its elements' linear sub-triangles, each edge once.
pub fn mean_edge(mesh: &crate::mesh::Mesh) -> f64 {
    let (triangles, _) = crate::bending::triangulate(mesh);
    let edges = crate::contact::proximity::edges_of(&triangles);
    let total: f64 = edges
        .iter()
        .map(|&[a, b]| crate::vec3::norm(crate::vec3::sub(mesh.nodes[a], mesh.nodes[b])))
        .sum();
    total / edges.len().max(1) as f64
}

/// Whether `model`'s mesh resolves its fabric's gravity bending length
/// `l` ([`crate::model::Model::bending_length`]) with `resolution` elements: its
/// [`mean_edge`] `h <= l / resolution`. A fold's crest bends the fabric
/// over a few `l`; a mesh much coarser cannot follow it, folds the fabric
/// fewer times and stiffer, and can change its drape coefficient less
/// than the tolerance from one such level to the next
/// (docs/validation.md, "The faille (F), and a convergence that was not
/// one"). `Ok` when `resolution` is 0 (nothing asked) or the mesh resolves it; else `Err((h, l /
/// resolution))`, the mean edge and the edge asked for (m).
pub fn resolved(model: &crate::model::Model, resolution: f64) -> Result<(), (f64, f64)> {
    if resolution <= 0.0 {
        return Ok(());
    }
    // The scenario's check ensures a bending length where one is asked.
    let Some(l) = model.bending_length() else {
        return Ok(());
    };
    let (h, asked) = (mean_edge(model.mesh()), l / resolution);
    if h <= asked { Ok(()) } else { Err((h, asked)) }
}

/// The summary's words on the levels: the drape coefficient per level, and
/// why the refinement stopped (and, where `resolution` says the last mesh
/// did not resolve the bending length, that it did not).
fn says(records: &[LevelRecord], converged: bool, resolution: Result<(), (f64, f64)>) -> String {
    let dcs: Vec<String> = records
        .iter()
        .map(|r| match r.drape_coefficient {
            Some(dc) => format!("{} T3: DC {dc:.4}", r.elements),
            None => format!("{} T3", r.elements),
        })
        .collect();
    let why = if converged {
        "the drape coefficient changed by less than refine.tolerance".to_string()
    } else if let Err((h, asked)) = resolution {
        format!(
            "refine.levels reached, the last mesh coarser than refine.resolution asks (mean edge {:.2} mm against {:.2} mm): not converged",
            1e3 * h,
            1e3 * asked
        )
    } else {
        "refine.levels reached".to_string()
    };
    format!("{} levels ({}); {why}", records.len(), dcs.join(", "))
}

/// A level that could not be made, recorded in the summary.
fn refine_error(out: &Path, level: usize, reason: String) -> RunError {
    let error = RunError::Refine {
        level,
        reason,
        out: out.to_path_buf(),
    };
    simulation::record_level_failure(out, &error.to_string());
    error
}

#[cfg(test)]
mod tests {
    use super::mean_edge;
    use crate::mesh::{ElementOrder, Mesh};

    /// The mean edge in closed form: a 3-4-5 triangle's is 4, each edge
    /// once; two such triangles sharing the hypotenuse (a 3 x 4
    /// rectangle) count it once, (3 + 4 + 3 + 4 + 5) / 5; a T6 triangle
    /// is measured by its four linear sub-triangles, whose nine edges
    /// average half its three.
    #[test]
    fn the_mean_edge_counts_each_edge_once() {
        let t3 = |nodes: Vec<[f64; 3]>, connectivity: Vec<usize>| Mesh {
            nodes,
            order: ElementOrder::Linear,
            connectivity,
        };
        let one = t3(
            vec![[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 4.0, 0.0]],
            vec![0, 1, 2],
        );
        assert!((mean_edge(&one) - 4.0).abs() < 1e-15);
        let two = t3(
            vec![
                [0.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [0.0, 4.0, 0.0],
                [3.0, 4.0, 0.0],
            ],
            vec![0, 1, 2, 1, 3, 2],
        );
        assert!((mean_edge(&two) - 19.0 / 5.0).abs() < 1e-15);
        let t6 = Mesh {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [0.0, 4.0, 0.0],
                [1.5, 0.0, 0.0],
                [1.5, 2.0, 0.0],
                [0.0, 2.0, 0.0],
            ],
            order: ElementOrder::Quadratic,
            connectivity: (0..6).collect(),
        };
        assert!((mean_edge(&t6) - 2.0).abs() < 1e-15);
    }
}
