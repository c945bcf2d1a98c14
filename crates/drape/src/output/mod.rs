//! Output files of a run.
//!
//! The output directory holds:
//!
//! - `summary.json` — the run summary, written elsewhere with
//!   [`atomic::write_atomic`];
//! - `history.csv` — one row per converged step, header line first; rows are
//!   appended and flushed one by one ([`history::HistoryWriter`]);
//! - `fields.pvd` + `fields/step_NNNNNN.vtu` — the ParaView time series: one
//!   VTK XML UnstructuredGrid per written step (6-digit zero-padded step
//!   number, [`pvd::frame_relative_path`]; raw binary appended data,
//!   [`vtu::write_vtu`]) and the collection file listing them with their
//!   times ([`pvd::PvdWriter`]).
//!
//! A crash never leaves a half-written file: `history.csv` is appended and
//! flushed per row, and every other file is written to a temporary name in
//! the same directory and then renamed over its final name
//! ([`atomic`]). A frame is written before it is added to `fields.pvd`, so
//! the collection only lists complete frames.
//!
//! [`directory`] makes the directory drape's own: one writer at a time
//! (a lock), and a fresh run that clears its previous outputs and refuses
//! anybody else's files.
//!
//! [`background::Background`] runs such writes on a thread of their own,
//! in order, so that a run loop need not wait for the disk.

pub mod atomic;
pub mod background;
pub mod directory;
pub mod history;
pub mod pvd;
pub mod vtu;
