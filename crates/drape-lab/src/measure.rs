//! A run directory's frame measured as a drape tester measures it (README,
//! "Measuring a drape"): `drape measure`, and each specimen of a drape
//! test.
//!
//! The frame is read with `drape-render`'s reader of output directories
//! (the collection `fields.pvd`, the frame's `.vtu`); the initial mesh is
//! the frame's positions less its `displacement`; the instrument is found
//! in the copy of the scenario the run keeps (`DIR/scenario.toml`) by
//! [`drape::measure::DrapeTester::find`]; [`drape::measure::measure`]
//! measures.

use anyhow::{Context, anyhow};
use drape::measure::{self, DrapeTester, Given, MeasureError, Measurement, Surface};
use drape::mesh::{ElementOrder, Mesh};
use drape::scenario::Scenario;
use drape_render::{FrameEntry, OutputDir};
use std::path::{Path, PathBuf};

/// One frame measured.
pub struct FrameMeasurement {
    /// The frame.
    pub entry: FrameEntry,
    /// The instrument it was measured in.
    pub tester: DrapeTester,
    /// What was found.
    pub measurement: Measurement,
}

/// A run's outputs opened for measuring: its frames and its scenario.
pub struct Run {
    /// The frames.
    pub out: OutputDir,
    /// `DIR/scenario.toml`, if there is one that reads.
    pub scenario: Option<Scenario>,
    /// Where the scenario was looked for.
    pub scenario_path: PathBuf,
    /// Radii given instead of found.
    pub given: Given,
}

impl Run {
    /// Opens `dir`'s frames and reads its scenario.
    ///
    /// # Errors
    /// A directory without frames; a scenario that does not read when a
    /// radius is still to be found in it. (One that does not read while
    /// both radii are given is left out, with a note on standard error.)
    pub fn open(dir: &Path, given: Given) -> anyhow::Result<Self> {
        let out =
            OutputDir::open(dir).with_context(|| format!("cannot measure {}", dir.display()))?;
        let scenario_path = out.dir.join("scenario.toml");
        let scenario = if scenario_path.exists() {
            match Scenario::read(&scenario_path) {
                Ok((s, _)) => Some(s),
                Err(e) if given.pedestal_radius.is_some() && given.specimen_radius.is_some() => {
                    eprintln!("note: {e}; measuring with the radii given and +z up");
                    None
                }
                Err(e) => return Err(e.into()),
            }
        } else {
            None
        };
        Ok(Self {
            out,
            scenario,
            scenario_path,
            given,
        })
    }

    /// Measures frame `index` of [`OutputDir::frames`].
    ///
    /// # Errors
    /// A frame that does not read, holds a value that is not finite or is
    /// not a triangle mesh of one order; an instrument that cannot be found
    /// (naming the scenario file).
    pub fn measure(&self, index: usize) -> anyhow::Result<FrameMeasurement> {
        let entry = self
            .out
            .frames
            .get(index)
            .ok_or_else(|| anyhow!("no frame {index} in {}", self.out.dir.display()))?
            .clone();
        let frame = drape_render::vtu::read_vtu(&entry.path)?;
        // A damaged frame would be measured as a wrong shadow, or none.
        frame.check_finite()?;
        let (connectivity, order) = elements(&frame)?;
        let initial = initial_positions(&frame)?;
        let mesh = Mesh {
            nodes: initial,
            order,
            connectivity,
        };
        let tester = DrapeTester::find(self.scenario.as_ref(), &mesh, entry.time, self.given)
            .map_err(|e| match e {
                // What the scenario lacks is said of the scenario.
                MeasureError::NoVertical { .. }
                | MeasureError::NoPedestal { .. }
                | MeasureError::AmbiguousPedestal { .. }
                | MeasureError::NotADisc { .. } => {
                    let found = if self.scenario.is_some() {
                        ""
                    } else {
                        " (not found)"
                    };
                    anyhow::Error::new(e)
                        .context(format!("{}{found}", self.scenario_path.display()))
                }
                e => anyhow::Error::new(e),
            })?;
        let surface = Surface {
            positions: &frame.points,
            connectivity: &mesh.connectivity,
            order,
        };
        let measurement = measure::measure(&surface, &tester)
            .with_context(|| format!("{}", entry.path.display()))?;
        Ok(FrameMeasurement {
            entry,
            tester,
            measurement,
        })
    }
}

/// The JSON object of `drape measure`, its keys in this order (README
/// "Measuring a drape"; keys are only ever added).
#[derive(serde::Serialize)]
pub struct Report {
    /// The frame's step.
    pub step: u64,
    /// Its time (s).
    pub time: f64,
    /// Shadow area `A` (m²).
    pub shadow_area: f64,
    /// `(A − π r_p²) / (π R² − π r_p²)`.
    pub drape_coefficient: f64,
    /// Waves round the rim.
    pub folds: usize,
    /// `r_p` (m).
    pub pedestal_radius: f64,
    /// `R` (m).
    pub specimen_radius: f64,
    /// Bound on the shadow area's error (m²).
    pub shadow_area_error_bound: f64,
    /// `"given"` or the obstacle, e.g. `"obstacle[0]"`.
    pub pedestal_radius_from: String,
    /// `"given"`, `"mesh.radius"` or `"initial rim"`.
    pub specimen_radius_from: String,
    /// The unit vertical.
    pub vertical: [f64; 3],
    /// The point on the pedestal's axis the plane is taken about (m).
    pub center: [f64; 3],
    /// The frame's file.
    pub frame: String,
    /// Edges of the fabric passing through its own triangles (0: it never
    /// crosses itself).
    pub crossings: usize,
}

impl Report {
    /// The report of a measured frame.
    pub fn of(m: &FrameMeasurement) -> Self {
        let t = &m.tester;
        Self {
            step: m.entry.step,
            time: m.entry.time,
            shadow_area: m.measurement.shadow_area,
            drape_coefficient: m.measurement.drape_coefficient,
            folds: m.measurement.folds,
            pedestal_radius: t.pedestal_radius,
            specimen_radius: t.specimen_radius,
            shadow_area_error_bound: m.measurement.shadow_area_error_bound,
            pedestal_radius_from: t.pedestal_source.clone(),
            specimen_radius_from: t.specimen_source.clone(),
            vertical: t.plane.vertical(),
            center: t.plane.origin(),
            frame: m.entry.path.display().to_string(),
            crossings: m.measurement.crossings,
        }
    }
}

/// The frame's connectivity and its one element order.
fn elements(frame: &drape_render::vtu::Frame) -> anyhow::Result<(Vec<usize>, ElementOrder)> {
    let count = frame.cell_count();
    if count == 0 {
        return Err(anyhow!("{}: no cells", frame.path.display()));
    }
    let n = frame.cell(0).len();
    let order = match n {
        3 => ElementOrder::Linear,
        6 => ElementOrder::Quadratic,
        10 => ElementOrder::Cubic,
        _ => return Err(anyhow!("{}: cell 0 has {n} nodes", frame.path.display())),
    };
    if let Some(c) = (0..count).find(|&c| frame.cell(c).len() != n) {
        return Err(anyhow!(
            "{}: cell {c} has {} nodes, cell 0 has {n}: elements of one order expected",
            frame.path.display(),
            frame.cell(c).len()
        ));
    }
    Ok((frame.connectivity.clone(), order))
}

/// The initial positions `X = x − u`, from the frame's `displacement`.
fn initial_positions(frame: &drape_render::vtu::Frame) -> anyhow::Result<Vec<[f64; 3]>> {
    let u = frame
        .point_array("displacement")
        .filter(|a| a.components == 3)
        .ok_or_else(|| {
            anyhow!(
                "{}: no point array \"displacement\" of 3 components (needed for the initial mesh)",
                frame.path.display()
            )
        })?;
    Ok(frame
        .points
        .iter()
        .zip(u.values.chunks_exact(3))
        .map(|(x, u)| [x[0] - u[0], x[1] - u[1], x[2] - u[2]])
        .collect())
}
