//! The error type of `gpodo-testbed`: a setting out of its domain, a
//! simulation that cannot continue, or an image or rover log that the
//! crates below refused.

/// Why the testbed could not be simulated, rendered or measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TestbedError {
    /// A setting or argument is out of its domain.
    #[error("invalid `{field}`: expected {expected}")]
    InvalidConfig {
        /// The setting's name.
        field: String,
        /// What would be accepted (may include the value found).
        expected: String,
    },
    /// The simulator could not continue (e.g. the chassis cannot be placed
    /// on terrain that is too steep).
    #[error("simulation failed: {detail}")]
    Simulation {
        /// What went wrong.
        detail: String,
    },
    /// An image could not be read or addressed.
    #[error(transparent)]
    Image(#[from] gpodo_vision::VisionError),
    /// A rover log or camera stream was refused by `gpodo-datasets`.
    #[error(transparent)]
    Dataset(#[from] gpodo_datasets::DatasetError),
    /// A gpodo data type rejected what it was given.
    #[error(transparent)]
    Model(#[from] gpodo_traits::Error),
}

/// `Ok(())` when `ok`, otherwise [`TestbedError::InvalidConfig`] naming
/// `field` and what was `expected`.
pub(crate) fn require(ok: bool, field: &str, expected: &str) -> Result<(), TestbedError> {
    if ok {
        Ok(())
    } else {
        Err(TestbedError::InvalidConfig {
            field: field.to_owned(),
            expected: expected.to_owned(),
        })
    }
}

impl From<gpodo_traits::InvalidCameraField> for TestbedError {
    fn from(e: gpodo_traits::InvalidCameraField) -> Self {
        Self::InvalidConfig {
            field: e.field,
            expected: e.expected,
        }
    }
}
