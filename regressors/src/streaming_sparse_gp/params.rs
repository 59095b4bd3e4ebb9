//! What a streaming sparse GP is asked to do, as written in YAML (`kind:
//! streaming_sparse_gp`), validated once when the configuration is read.

use serde::{Deserialize, Serialize};

use crate::RegressorError;
use crate::hyperopt::HyperoptParams;
use crate::kernels::{KernelExpr, KernelInit, LeafName};
use crate::sparse_gp::InducingParams;

/// Streaming sparse GP settings. Every field has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StreamingSparseGpParams {
    /// Kernel expression (default `rbf`).
    pub kernel: KernelExpr,
    /// The inducing inputs: `count` is the most a batch keeps (default
    /// 100), `init` and `kmeans_iters` place the first batch's, and
    /// `fixed` keeps every batch's where they were placed (default false:
    /// each batch learns its own with the hyperparameters).
    pub inducing: InducingParams,
    /// The share of `inducing.count` kept from the previous batch once
    /// there are that many (default 0.7, as the authors' experiments);
    /// the rest are the new batch's inputs. Before there are that many,
    /// every old one is kept and the new batch's inputs are added.
    pub kept_inducing: f64,
    /// Rows of the first batch (default 100): its z-scoring is used for
    /// good, and its hyperparameters and inducing inputs are learned with
    /// the full `hyperopt` recipe (the streaming bound is then the batch
    /// VFE bound). Until it is complete the model predicts the rows' mean
    /// and variance.
    pub warmup_rows: usize,
    /// Rows of each later batch (default 10: ten 1-s rows, one batch of
    /// visual-odometry targets every 10 s).
    pub batch_rows: usize,
    /// L-BFGS iterations on a later batch's bound, from the previous
    /// hyperparameters and the kept-and-added inducing inputs, with
    /// `hyperopt`'s tolerances and bounds (default 20; 0 keeps the
    /// hyperparameters and the inducing inputs as placed).
    pub batch_iters: u64,
    /// The most one later batch moves each log-hyperparameter (the noise
    /// variance's included) from where the previous batch left it, within
    /// `hyperopt.bounds` (default 0.5: a factor of 1.65). Ten rows say
    /// little about a kernel: unbounded, the signal variance and the
    /// lengthscales of a batch run to their bounds, and the summary's
    /// precision with them.
    pub batch_log_step: f64,
    /// Z-score inputs and outputs with the first batch's statistics
    /// (default true).
    pub standardize: bool,
    /// Initial kernel hyperparameters.
    pub init: KernelInit,
    /// Initial noise variance in standardised units (default 0.01).
    pub noise_variance: f64,
    /// Diagonal jitter added to the inducing points' prior covariances
    /// (default 1e-6, as the sparse GP).
    pub jitter: f64,
    /// How the first batch's hyperparameters are learned (the sparse GP's
    /// recipe), and the bounds and tolerances of every later batch's.
    pub hyperopt: HyperoptParams,
    /// Seed of the first placement, the start race and which inducing
    /// inputs each batch keeps and adds (default 0).
    pub seed: u64,
}

impl Default for StreamingSparseGpParams {
    fn default() -> Self {
        Self {
            kernel: KernelExpr::Leaf(LeafName::Rbf),
            inducing: InducingParams::default(),
            kept_inducing: 0.7,
            warmup_rows: 100,
            batch_rows: 10,
            batch_iters: 20,
            batch_log_step: 0.5,
            standardize: true,
            init: KernelInit::default(),
            noise_variance: 0.01,
            jitter: 1e-6,
            hyperopt: HyperoptParams::default(),
            seed: 0,
        }
    }
}

impl StreamingSparseGpParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field and the expected form.
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "streaming_sparse_gp".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.inducing.count == 0 {
            return bad("inducing.count", "at least 1 inducing point");
        }
        if !(self.kept_inducing >= 0.0 && self.kept_inducing < 1.0) {
            return bad(
                "kept_inducing",
                "a share in [0, 1): the rest of each batch's inducing inputs are new",
            );
        }
        if self.warmup_rows < 2 {
            return bad("warmup_rows", "at least 2 rows");
        }
        if self.batch_rows == 0 {
            return bad("batch_rows", "at least 1 row");
        }
        if !(self.batch_log_step.is_finite() && self.batch_log_step > 0.0) {
            return bad("batch_log_step", "a positive step in log units");
        }
        if !(self.jitter.is_finite() && self.jitter >= 0.0) {
            return bad("jitter", "a non-negative number");
        }
        self.hyperopt
            .check("streaming_sparse_gp", true, &self.init, self.noise_variance)
    }
}
