//! Errors of the regressors crate.

/// Why a regressor could not be built or evaluated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RegressorError {
    /// A specification field has an invalid value.
    #[error("invalid regressor `{regressor}`: field `{field}`: expected {expected}")]
    InvalidSpec {
        /// The regressor's kind.
        regressor: String,
        /// The offending field.
        field: String,
        /// What a valid value looks like.
        expected: String,
    },
    /// Predictions and targets do not have the same shape.
    #[error("cannot score predictions of shape {predicted:?} against targets of shape {targets:?}")]
    ShapeMismatch {
        /// `(rows, cols)` of the predictions.
        predicted: (usize, usize),
        /// `(rows, cols)` of the targets.
        targets: (usize, usize),
    },
    /// There is nothing to score.
    #[error("cannot score an empty test set")]
    EmptyTestSet,
    /// A kernel matrix stayed indefinite after the largest jitter.
    #[error(
        "kernel matrix of size {n} is not positive definite, even with a diagonal jitter of {jitter_tried:e}"
    )]
    NotPositiveDefinite {
        /// Matrix size.
        n: usize,
        /// The largest jitter tried.
        jitter_tried: f64,
    },
    /// The training data cannot be used (empty, non-finite, wrong width).
    #[error("training data: {detail}")]
    InvalidData {
        /// What is wrong, naming the row and column where there is one.
        detail: String,
    },
    /// The hyperparameter optimiser failed.
    #[error("hyperparameter optimisation ({optimizer}): {detail}")]
    Optimizer {
        /// Which optimiser.
        optimizer: String,
        /// What went wrong.
        detail: String,
    },
    /// Standardising the data failed.
    #[error(transparent)]
    Standardize(#[from] gpodo_traits::Error),
}

impl From<RegressorError> for gpodo_traits::Error {
    fn from(e: RegressorError) -> Self {
        gpodo_traits::Error::Backend(Box::new(e))
    }
}
