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
    /// The fit was stopped from outside (its progress observer asked it
    /// to); nothing was fitted.
    #[error("the fit was stopped before it ended; nothing was fitted")]
    Stopped,
    /// The hyperparameter optimiser failed.
    #[error("hyperparameter optimisation ({optimizer}): {detail}")]
    Optimizer {
        /// Which optimiser.
        optimizer: String,
        /// What went wrong.
        detail: String,
    },
    /// An external regressor's plugin failed: it crashed, hung, replied
    /// with something that is not the protocol, or refused the request.
    #[error(
        "external regressor `{regressor}`, request `{request}`: {detail}{}",
        stderr_block(stderr)
    )]
    Plugin {
        /// The regressor's label.
        regressor: String,
        /// The request that failed (`hello`, `fit`, `predict`, `update`).
        request: String,
        /// What went wrong.
        detail: String,
        /// The plugin's last stderr lines.
        stderr: Vec<String>,
    },
    /// Standardising the data failed.
    #[error(transparent)]
    Standardize(#[from] gpodo_traits::Error),
}

/// The plugin's last stderr lines, indented under the message.
fn stderr_block(lines: &[String]) -> String {
    if lines.is_empty() {
        return "; the plugin wrote nothing to stderr".into();
    }
    let mut out = String::from("; the plugin's last stderr lines:");
    for line in lines {
        out.push_str("\n  | ");
        out.push_str(line);
    }
    out
}

impl From<RegressorError> for gpodo_traits::Error {
    fn from(e: RegressorError) -> Self {
        gpodo_traits::Error::Backend(Box::new(e))
    }
}
