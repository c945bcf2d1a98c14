//! The field frames of a run (`fields/step_NNNNNN.vtu` and `fields.pvd`),
//! written off the run loop.
//!
//! The loop hands over an owned [`Snapshot`] of what a frame shows and goes
//! on with the next step; a writer thread ([`Background`]) derives the
//! element results from the positions, writes the VTU and then adds it to
//! the collection — one frame after the other, in submission order, so
//! the collection never names a frame that is not complete on disk. The
//! element results are pure functions of the positions, so the frames are
//! the same, to the bit, as when they were written on the loop's thread.

use super::{RunError, io_err};
use crate::contact::ContactReport;
use crate::integrator::State;
use crate::model::Model;
use crate::output::background::Background;
use crate::output::pvd::{PvdWriter, frame_relative_path};
use crate::output::vtu::{DataArray, Frame, Values, write_vtu};
use std::path::Path;
use std::thread::Scope;

/// Frames that may wait for the writer thread before the run loop blocks:
/// enough to ride out one slow sync, few enough that the snapshots of a
/// large mesh (three copies of the unknowns each) cost little memory.
const QUEUED_FRAMES: usize = 2;

/// What a frame shows, owned so that the run loop can go on at once.
#[derive(Debug, Clone)]
pub(super) struct Snapshot {
    /// Converged step (names the file).
    pub step: usize,
    /// Time (s), or load factor in statics.
    pub time: f64,
    /// Positions `Y` (m), flattened.
    pub positions: Vec<f64>,
    /// Velocities `V` (m/s), flattened.
    pub velocities: Vec<f64>,
    /// Contact force on each node (N); `None` without obstacles.
    pub contact_forces: Option<Vec<[f64; 3]>>,
}

impl Snapshot {
    /// A copy of what the frame of `state` at `step` needs.
    pub fn of(step: usize, state: &State, contact: Option<&ContactReport>) -> Self {
        Self {
            step,
            time: state.time,
            positions: state.positions.clone(),
            velocities: state.velocities.clone(),
            contact_forces: contact.map(|c| c.nodal_forces.clone()),
        }
    }
}

/// The writer thread of a run's frames.
pub(super) type FrameWriter<'scope> = Background<'scope, Snapshot, RunError>;

/// Starts the writer thread of the frames of `model` into `dir`, adding
/// each to `pvd` once it is on disk.
///
/// # Errors
/// The operating system's, if it cannot create the thread.
pub(super) fn spawn<'scope>(
    scope: &'scope Scope<'scope, '_>,
    model: &'scope Model,
    dir: &'scope Path,
    mut pvd: PvdWriter,
) -> std::io::Result<FrameWriter<'scope>> {
    Background::spawn(scope, "drape-frames", QUEUED_FRAMES, move |s: Snapshot| {
        write_frame(model, dir, &mut pvd, &s)
    })
}

/// Writes the frame `s` to `dir/fields/step_NNNNNN.vtu`, then adds it to
/// the collection `pvd`.
fn write_frame(
    model: &Model,
    dir: &Path,
    pvd: &mut PvdWriter,
    s: &Snapshot,
) -> Result<(), RunError> {
    let (positions, _) = s.positions.as_chunks::<3>();
    let displacement: Vec<f64> = s
        .positions
        .iter()
        .zip(model.mesh().nodes.iter().flatten())
        .map(|(y, x)| y - x)
        .collect();
    let no_contact;
    let contact: &[f64] = match &s.contact_forces {
        Some(f) => f.as_flattened(),
        None => {
            no_contact = vec![0.0; s.positions.len()];
            &no_contact
        }
    };
    let results = model.element_results(&s.positions);
    let rel = frame_relative_path(s.step as u64);
    let path = dir.join(&rel);
    let frame = Frame {
        positions,
        connectivity: &model.mesh().connectivity,
        nodes_per_element: model.mesh().order.nodes_per_element(),
        point_data: vec![
            DataArray {
                name: "displacement",
                components: 3,
                values: Values::F64(&displacement),
                component_names: &[],
            },
            DataArray {
                name: "velocity",
                components: 3,
                values: Values::F64(&s.velocities),
                component_names: &[],
            },
            DataArray {
                name: "contact_force",
                components: 3,
                values: Values::F64(contact),
                component_names: &[],
            },
        ],
        cell_data: vec![
            DataArray {
                name: "stress",
                components: 3,
                values: Values::F64(results.stress.as_flattened()),
                component_names: &["xx", "yy", "xy"],
            },
            DataArray {
                name: "principal_stress",
                components: 2,
                values: Values::F64(results.principal.as_flattened()),
                component_names: &["max", "min"],
            },
            DataArray {
                name: "wrinkle_state",
                components: 1,
                values: Values::I32(&results.state),
                component_names: &[],
            },
        ],
        time: s.time,
    };
    write_vtu(&path, &frame).map_err(io_err(&path))?;
    let pvd_path = pvd.path().to_path_buf();
    pvd.push(s.time, &rel).map_err(io_err(&pvd_path))
}
