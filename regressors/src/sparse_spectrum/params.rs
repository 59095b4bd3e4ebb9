//! What a sparse-spectrum GP is asked to do, as written in YAML (`kind:
//! sparse_spectrum`), validated once when the configuration is read.

use serde::{Deserialize, Serialize};

use crate::RegressorError;
use crate::hyperopt::HyperoptParams;
use crate::kernels::{KernelExpr, LeafName};

/// Sparse-spectrum GP settings (I-SSGP). Every field has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SparseSpectrumParams {
    /// The stationary ARD kernel whose spectral density the features sample:
    /// `rbf` (default), `matern52` or `matern32`.
    pub kernel: KernelExpr,
    /// Random features `D` (default 200): `D/2` frequencies, each giving a
    /// cosine and a sine.
    pub features: usize,
    /// Rows at the stream's start whose batch exact-GP fit sets the
    /// hyperparameters and the input and target scaling (default 200);
    /// no later row ever changes them.
    pub warmup_rows: usize,
    /// Forgetting factor `λ ∈ (0, 1]` applied to the accumulated statistics
    /// before each update (default 1: never forget).
    pub forgetting: f64,
    /// Seed of the random frequencies (default 0).
    pub seed: u64,
    /// How the warm-up GP learns its hyperparameters.
    pub hyperopt: HyperoptParams,
}

impl Default for SparseSpectrumParams {
    fn default() -> Self {
        Self {
            kernel: KernelExpr::Leaf(LeafName::Rbf),
            features: 200,
            warmup_rows: 200,
            forgetting: 1.0,
            seed: 0,
            hyperopt: HyperoptParams::default(),
        }
    }
}

impl SparseSpectrumParams {
    /// The kernel's leaf, if it is one the features can sample.
    pub fn leaf(&self) -> Option<LeafName> {
        match self.kernel {
            KernelExpr::Leaf(leaf @ (LeafName::Rbf | LeafName::Matern52 | LeafName::Matern32)) => {
                Some(leaf)
            }
            _ => None,
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field and the expected form.
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "sparse_spectrum".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.leaf().is_none() {
            return bad("kernel", "one stationary kernel: rbf, matern52 or matern32");
        }
        if self.features < 2 || !self.features.is_multiple_of(2) {
            return bad("features", "an even number of random features, at least 2");
        }
        if self.warmup_rows < 2 {
            return bad("warmup_rows", "at least 2 rows");
        }
        if !(self.forgetting > 0.0 && self.forgetting <= 1.0) {
            return bad("forgetting", "a factor in (0, 1]");
        }
        let init = crate::kernels::KernelInit::default();
        self.hyperopt.check("sparse_spectrum", true, &init, 0.01)
    }
}
