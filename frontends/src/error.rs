//! Errors of the frontends crate.

/// Why a front-end component could not be built or run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FrontendError {
    /// A specification field has an invalid value.
    #[error("invalid selector `{selector}`: field `{field}`: expected {expected}")]
    InvalidSpec {
        /// The selector's kind.
        selector: String,
        /// The offending field.
        field: String,
        /// What a valid value looks like.
        expected: String,
    },
    /// A front-end setting (visual odometry, keyframes, back end) is invalid.
    #[error("invalid front-end setting `{field}`: expected {expected}")]
    InvalidConfig {
        /// The offending field, dotted (`vo.hfov_rad`).
        field: String,
        /// What a valid value looks like.
        expected: String,
    },
    /// The traverse handed to the front end is inconsistent.
    #[error("invalid traverse `{traverse}`: {detail}")]
    InvalidTraverse {
        /// The traverse's name.
        traverse: String,
        /// What is wrong.
        detail: String,
    },
    /// A file (trajectory, VO log) could not be parsed.
    #[error("{path}:{line}: {detail}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// What was expected.
        detail: String,
    },
    /// The regressor that feeds a gating policy failed.
    #[error("residual regressor: {0}")]
    Regressor(#[from] gpodo_traits::Error),
    /// The pose-graph optimisation failed.
    #[error("pose-graph optimisation failed: {0}")]
    Backend(String),
}

impl From<gpodo_traits::InvalidCameraField> for FrontendError {
    fn from(e: gpodo_traits::InvalidCameraField) -> Self {
        Self::InvalidConfig {
            field: e.field,
            expected: e.expected,
        }
    }
}
