//! The regressor kinds an experiment may name in YAML, as a closed enum
//! (`kind: zero`, ...). A spec is validated when the configuration is read
//! and then built into a runtime `Box<dyn ResidualRegressor>`.

use gpodo_traits::ResidualRegressor;
use serde::{Deserialize, Serialize};

use crate::{RegressorError, ZeroResidual};

/// A regressor as written in an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RegressorSpec {
    /// "Parametric model only": zero residual.
    Zero {
        /// Fixed predictive variance per output ((m/s)²); omitted, the
        /// training residuals' mean square per output.
        #[serde(default)]
        variance: Option<f64>,
    },
}

impl RegressorSpec {
    /// A short label for reports.
    pub fn label(&self) -> String {
        match self {
            Self::Zero { .. } => "parametric only".into(),
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), RegressorError> {
        match self {
            Self::Zero { variance: Some(v) } if !(v.is_finite() && *v > 0.0) => {
                Err(RegressorError::InvalidSpec {
                    regressor: "zero".into(),
                    field: "variance".into(),
                    expected: "a positive variance in (m/s)²".into(),
                })
            }
            Self::Zero { .. } => Ok(()),
        }
    }

    /// Builds the runtime regressor.
    ///
    /// # Errors
    /// As [`RegressorSpec::validate`].
    pub fn build(&self) -> Result<Box<dyn ResidualRegressor>, RegressorError> {
        self.validate()?;
        Ok(match self {
            Self::Zero { variance } => Box::new(ZeroResidual::new(*variance)),
        })
    }
}
