//! The output directory held for one session of a run, as both front ends
//! (the command line and Python) hold it: locked — a resume's before
//! anything is read, so that a refusal can be recorded without racing
//! another writer —, a fresh run's previous outputs cleared and its
//! scenario kept (`scenario.toml`, `scenario.path`), a refused resume
//! recorded in the summary ([`Session`]).
//!
//! A front end names itself ([`Front`]) so that the messages tell its user
//! how to ask for what they suggest: "without --resume" on the command
//! line, "resume=False" in Python.

use super::RunControl;
use super::checkpoint::{path_from_bytes, path_to_bytes};
use super::start::ResumeError;
use super::summary::{record_failure, record_refused_resume};
use crate::output::atomic::write_atomic;
use crate::output::directory::{self, DirectoryError, OutputLock, SCENARIO_COPY, SCENARIO_PATH};
use crate::setup::Setup;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// Which front end drives the library: the words its messages use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Front {
    /// `drape run`.
    #[default]
    CommandLine,
    /// `drape.run` of the Python package.
    Python,
}

impl Front {
    /// How this front end asks for a fresh run into the same directory.
    pub fn fresh_run(self) -> &'static str {
        match self {
            Front::CommandLine => "without --resume",
            Front::Python => "resume=False",
        }
    }
}

/// A [`ResumeError`] in a front end's words: the way to a fresh run
/// named where the message suggests one.
pub struct Explained<'a> {
    /// Why the resume is refused.
    pub error: &'a ResumeError,
    /// Whose user reads it.
    pub front: Front,
}

impl fmt::Display for Explained<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.error)?;
        if self.error.suggests_fresh_run() {
            write!(f, " ({})", self.front.fresh_run())?;
        }
        Ok(())
    }
}

/// An output directory held by one session of a run, until dropped.
#[derive(Debug)]
pub struct Session {
    lock: OutputLock,
    dir: PathBuf,
    front: Front,
    resume: bool,
}

impl Session {
    /// Takes `dir` for a fresh run (creating it), refused at once if
    /// another process holds it. Its previous outputs stay until
    /// [`Session::start_fresh`].
    pub fn fresh(dir: &Path, front: Front) -> Result<Self, DirectoryError> {
        Ok(Self {
            lock: directory::lock(dir)?,
            dir: dir.to_path_buf(),
            front,
            resume: false,
        })
    }

    /// Takes `dir`, which must hold a run, to resume it; nothing is created
    /// in a directory that does not.
    pub fn resume(dir: &Path, front: Front) -> Result<Self, DirectoryError> {
        Ok(Self {
            lock: directory::lock_resume(dir)?,
            dir: dir.to_path_buf(),
            front,
            resume: true,
        })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Whether the session resumes a run.
    pub fn resumes(&self) -> bool {
        self.resume
    }

    /// How the run loop is to go on in this session: from the checkpoint
    /// or not, stopped by `stop`, its messages in this front end's words.
    pub fn control<'a>(&self, stop: Option<&'a AtomicBool>) -> RunControl<'a> {
        RunControl {
            stop,
            resume: self.resume,
            front: self.front,
            progress: None,
        }
    }

    /// A fresh run's clean slate: the directory must hold only drape's
    /// outputs (and `scenario_file`, the file being run, which may lie
    /// there), and the previous run's are removed.
    pub fn start_fresh(&self, scenario_file: Option<&Path>) -> Result<(), DirectoryError> {
        directory::clear_previous_outputs(&self.lock, &self.dir, scenario_file)
    }

    /// Keeps the scenario for `--resume` and for readers of the outputs:
    /// `scenario.toml` holds `text` (unless `file`, the scenario's own file,
    /// is that very file) and `scenario.path` the absolute path of `file`,
    /// or of the copy for a scenario without a file, in the path's own
    /// bytes (a name that is not UTF-8 must be found again). A failure is
    /// recorded in the summary (the directory is drape's) and returned as
    /// the message, which says so if the summary could not be written.
    pub fn keep_scenario(
        &self,
        file: Option<&Path>,
        text: &str,
        setup: &Setup,
    ) -> Result<(), String> {
        let copy = self.dir.join(SCENARIO_COPY);
        let kept = (|| {
            // Never write a file onto itself (a sweep's case runs its
            // scenario where its outputs go).
            if file
                .is_none_or(|f| std::fs::canonicalize(f).ok() != std::fs::canonicalize(&copy).ok())
            {
                write_atomic(&copy, text.as_bytes())?;
            }
            let original = std::fs::canonicalize(file.unwrap_or(&copy))?;
            write_atomic(&self.dir.join(SCENARIO_PATH), &path_to_bytes(&original))
        })();
        kept.map_err(|e| {
            let message = format!("cannot write into {}: {e}", self.dir.display());
            match record_failure(&self.dir, Some(setup), false, &message) {
                Ok(()) => message,
                Err(s) => format!(
                    "{message}; and {} could not be written: {s}",
                    self.summary()
                ),
            }
        })
    }

    /// The scenario file the run in this directory was started with, as
    /// `scenario.path` records it.
    pub fn started_with(&self) -> std::io::Result<PathBuf> {
        let bytes = std::fs::read(self.dir.join(SCENARIO_PATH))?;
        let bytes = bytes.strip_suffix(b"\n").unwrap_or(&bytes);
        let bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        Ok(path_from_bytes(bytes))
    }

    /// Before a resume is set up: a completed run must have kept a
    /// checkpoint, and each input file the checkpoint recorded must be as it was
    /// ([`super::check_resume_inputs`]); a refusal is
    /// recorded ([`Session::refuse`]) and its message returned.
    pub fn check_inputs(&self) -> Result<(), String> {
        super::check_resume_inputs(&self.dir).map_err(|error| {
            let why = Explained {
                error: &error,
                front: self.front,
            };
            self.refuse(&why).unwrap_or_else(|unrecorded| unrecorded)
        })
    }

    /// Records a resume refused for `why` in the summary (status
    /// "failed", the interrupted session's counts kept; a completed run's
    /// summary is left alone) and returns the message, "cannot resume:
    /// {why}"; or, if the summary could not be written, the message
    /// saying so.
    pub fn refuse(&self, why: &dyn fmt::Display) -> Result<String, String> {
        record_refused_resume(&self.dir, why).map_err(|e| {
            format!(
                "cannot resume: {why}; and {} could not be written: {e}",
                self.summary()
            )
        })
    }

    fn summary(&self) -> String {
        self.dir.join("summary.json").display().to_string()
    }
}
