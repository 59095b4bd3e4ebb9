//! Errors of the kinematics crate.

/// What went wrong while reading a rover description or solving the model.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum KinematicsError {
    /// A rover description field has an invalid value.
    #[error("invalid rover description: field `{field}`: expected {expected}")]
    InvalidDescription {
        /// The offending field (e.g. `wheels[2].bogie`).
        field: String,
        /// What a valid value looks like.
        expected: String,
    },
    /// The rover description YAML could not be parsed.
    #[error("cannot parse rover description {source_name}: {detail}")]
    Yaml {
        /// The file (or `<embedded>`) the YAML came from.
        source_name: String,
        /// The parser's message, with line and column.
        detail: String,
    },
    /// A model configuration field has an invalid value.
    #[error("invalid motion model configuration: field `{field}`: expected {expected}")]
    InvalidConfig {
        /// The offending field.
        field: String,
        /// What a valid value looks like.
        expected: String,
    },
    /// The (weighted) least-squares or QP solve failed.
    #[error("motion model solve failed: {0}")]
    Solve(String),
}

impl From<KinematicsError> for gpodo_traits::Error {
    fn from(e: KinematicsError) -> Self {
        match e {
            KinematicsError::Solve(detail) => gpodo_traits::Error::Numerical {
                context: "motion model".into(),
                detail,
            },
            other => gpodo_traits::Error::Backend(Box::new(other)),
        }
    }
}
