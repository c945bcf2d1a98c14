//! Why faer failed to analyse or factorise a pattern, whatever its values
//! ([`FaerFailure`]): a cause of the direct solves' errors and of the block
//! LU's ordering.

use faer::sparse::FaerError;

/// Why faer failed whatever the values: [`FaerError`] in words.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaerFailure {
    /// An allocation failed.
    OutOfMemory,
    /// An index exceeded what the index type holds.
    IndexOverflow,
    /// A reason this version of drape does not know.
    Other,
}

impl From<FaerError> for FaerFailure {
    fn from(e: FaerError) -> Self {
        match e {
            FaerError::OutOfMemory => FaerFailure::OutOfMemory,
            FaerError::IndexOverflow => FaerFailure::IndexOverflow,
            _ => FaerFailure::Other,
        }
    }
}

impl std::fmt::Display for FaerFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FaerFailure::OutOfMemory => "out of memory",
            FaerFailure::IndexOverflow => "an index overflowed",
            FaerFailure::Other => "an unknown error",
        })
    }
}
