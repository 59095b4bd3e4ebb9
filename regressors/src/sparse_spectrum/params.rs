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
    /// Prior variance `σ_b²` (scaled target units) of a constant feature
    /// beside the random ones, i.e. the kernel `k + σ_b²`: an offset the
    /// stream's targets drift to is learned as a weight, where the random
    /// features alone revert to the warm-up rows' mean (default 0: none).
    pub bias_variance: f64,
    /// Learn the noise variance from the stream (default true): a
    /// Normal-inverse-Gamma posterior over the weights and `σ²`, conjugate,
    /// with the warm-up's `σ_n²` as its prior mean; predictions are then
    /// Student-t and reported by their variance. False keeps the warm-up's
    /// `σ_n²` for good.
    pub learn_noise: bool,
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
            bias_variance: 0.0,
            learn_noise: true,
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
            // No spectral density to sample features from: a stationary
            // kernel's is needed (Bochner), and a new leaf must be decided.
            KernelExpr::Leaf(LeafName::Linear | LeafName::White | LeafName::RatQuad)
            | KernelExpr::Sum(_)
            | KernelExpr::Product(_) => None,
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
        if !(self.bias_variance >= 0.0 && self.bias_variance.is_finite()) {
            return bad(
                "bias_variance",
                "a finite variance ≥ 0 (0: no constant feature)",
            );
        }
        let init = crate::kernels::KernelInit::default();
        self.hyperopt.check("sparse_spectrum", true, &init, 0.01)
    }
}
