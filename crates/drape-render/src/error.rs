//! The one error type of the crate.

use std::path::PathBuf;

/// Everything that can go wrong while reading an output directory, a
/// scenario file, or writing an image. Each variant names the file (or the
/// option) and the problem.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A file could not be read or written.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error (in the message, so not also a
        /// `source`: chains would print it twice).
        error: std::io::Error,
    },
    /// A file was read but its content is not what drape writes.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where.
        message: String,
    },
    /// The output directory has no frame to render.
    #[error("{}: no frames (is this a drape output directory? it has no fields.pvd entries)", path.display())]
    NoFrames {
        /// The collection file.
        path: PathBuf,
    },
    /// `--step` names a step that was not written.
    #[error("{}: step {step} was not written; written steps: {available}", path.display())]
    StepNotFound {
        /// The collection file.
        path: PathBuf,
        /// The requested step.
        step: u64,
        /// A short list of the steps that exist.
        available: String,
    },
    /// A frame lacks the array a field needs.
    #[error("{}: no {kind} array {array:?} (needed for the field {field})", path.display())]
    MissingArray {
        /// The `.vtu` file.
        path: PathBuf,
        /// `point` or `cell`.
        kind: &'static str,
        /// The array's name.
        array: String,
        /// The field being rendered.
        field: String,
    },
    /// The scenario file (for obstacles) is not usable.
    #[error("{}: {message}", path.display())]
    Scenario {
        /// The scenario file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An option value is not valid.
    #[error("{0}")]
    InvalidOption(String),
    /// Encoding the PNG or GIF failed.
    #[error("{}: cannot encode the image: {message}", path.display())]
    Encode {
        /// The image file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

impl RenderError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        RenderError::Io {
            path: path.into(),
            error: source,
        }
    }

    pub(crate) fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        RenderError::Format {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Shorthand for results of this crate.
pub type Result<T, E = RenderError> = std::result::Result<T, E>;
