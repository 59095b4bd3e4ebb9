//! The error type every trait method of gpodo returns.

/// Why a motion model, regressor or frame selector could not do what was asked.
///
/// Implementations in other crates map their own errors into these variants;
/// [`Error::Backend`] carries anything that does not fit, with its source.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An input had the wrong dimension.
    #[error("{what}: expected dimension {expected}, found {found}")]
    DimensionMismatch {
        /// What was being checked (e.g. `"wheel rates"`).
        what: String,
        /// The dimension the implementation needs.
        expected: usize,
        /// The dimension it was given.
        found: usize,
    },
    /// An input value was not finite or out of its domain.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A numerical routine failed (singular system, solver failure, ...).
    #[error("numerical failure in {context}: {detail}")]
    Numerical {
        /// Which computation failed.
        context: String,
        /// What went wrong.
        detail: String,
    },
    /// `predict` or `update` was called before `fit`.
    #[error("model `{model}` has not been fitted")]
    NotFitted {
        /// The model's name.
        model: String,
    },
    /// The model cannot learn one sample at a time.
    #[error("model `{model}` does not support online updates")]
    OnlineUpdateUnsupported {
        /// The model's name.
        model: String,
    },
    /// An implementation-specific failure, with its source.
    #[error(transparent)]
    Backend(Box<dyn std::error::Error + Send + Sync>),
}
