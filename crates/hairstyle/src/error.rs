//! Errors of hairstyle generation.

use crate::head::HeadError;
use lattice::ffd::FfdError;
use strand::StrandError;
use thiserror::Error;

/// Errors of hairstyle generation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GenerateError {
    /// A parameter is out of range; `field` names it.
    #[error("invalid hairstyle parameter `{field}`: {reason}")]
    InvalidParameter {
        /// Parameter name.
        field: &'static str,
        /// What is wrong, with the value.
        reason: String,
    },
    /// The head parameters are invalid.
    #[error(transparent)]
    Head(#[from] HeadError),
    /// A guide strand could not be built.
    #[error("guide {guide}: {source}")]
    Strand {
        /// Guide index.
        guide: usize,
        /// The strand crate's error.
        source: StrandError,
    },
    /// A hair file's strand cannot be used as a render strand.
    #[error("strand {strand} of the hair file: {reason}")]
    BadStrand {
        /// Strand index in the file.
        strand: usize,
        /// What is wrong.
        reason: String,
    },
    /// Binding to the lattice failed.
    #[error(transparent)]
    Ffd(#[from] FfdError),
}
