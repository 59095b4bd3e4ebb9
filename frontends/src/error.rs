//! Errors of the frontends crate.

/// Why a front-end component could not be built.
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
}
