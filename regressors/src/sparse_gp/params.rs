//! What a sparse GP is asked to do, as written in YAML (`kind: sparse_gp`),
//! validated once when the configuration is read. Defaults follow the
//! authors' on-board model (GPy `SparseGPRegression`: RBF-ARD, 100 inducing
//! points, hyperparameters shared by the outputs, L-BFGS-B on the bound).

use serde::{Deserialize, Serialize};

use crate::RegressorError;
use crate::hyperopt::HyperoptParams;
use crate::kernels::{KernelExpr, KernelInit, LeafName};

/// Which sparse approximation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Approximation {
    /// Titsias' collapsed variational bound (VFE, GPy's `VarDTC`): a lower
    /// bound on the exact log marginal likelihood. Default.
    #[default]
    Vfe,
    /// Fully independent training conditional (Snelson & Ghahramani): the
    /// exact likelihood of a heteroscedastic approximate model.
    Fitc,
}

/// How the inducing inputs are first placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InducingInit {
    /// k-means centres (k-means++ seeding, then Lloyd iterations). Default.
    #[default]
    Kmeans,
    /// A random subset of the training inputs.
    RandomSubset,
}

/// The inducing inputs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InducingParams {
    /// Number of inducing points `m` (default 100; all training points
    /// when there are fewer).
    pub count: usize,
    /// Initial placement (default `kmeans`).
    pub init: InducingInit,
    /// Lloyd iterations of the k-means placement (default 25).
    pub kmeans_iters: usize,
    /// Keep the inducing inputs where they were placed (default false:
    /// they are learned with the hyperparameters).
    pub fixed: bool,
}

impl Default for InducingParams {
    fn default() -> Self {
        Self {
            count: 100,
            init: InducingInit::Kmeans,
            kmeans_iters: 25,
            fixed: false,
        }
    }
}

/// Sparse GP settings. Every field has a default; see `experiments/README.md`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SparseGpParams {
    /// Kernel expression (default `rbf`).
    pub kernel: KernelExpr,
    /// Approximation (default `vfe`).
    pub approximation: Approximation,
    /// Inducing inputs.
    pub inducing: InducingParams,
    /// Z-score inputs and outputs with training statistics (default true).
    pub standardize: bool,
    /// Initial kernel hyperparameters.
    pub init: KernelInit,
    /// Initial noise variance in standardised units (default 0.01).
    pub noise_variance: f64,
    /// Diagonal jitter added to `K_uu` in standardised units (default 1e-6,
    /// GPy's FITC constant; GPy's VFE (`VarDTC`) adds 1e-8, which learned
    /// inducing inputs that drift together can make too small).
    pub jitter: f64,
    /// Learn the hyperparameters (and the inducing inputs unless fixed)
    /// (default true).
    pub optimize: bool,
    /// How the hyperparameters (and inducing inputs) are learned: the
    /// exact GP's settings, except that the start race is not halved
    /// unless `start.halve_after` says so.
    pub hyperopt: HyperoptParams,
    /// Seed of the inducing-point placement, the candidate starts and the
    /// restarts (default 0).
    pub seed: u64,
}

impl Default for SparseGpParams {
    fn default() -> Self {
        Self {
            kernel: KernelExpr::Leaf(LeafName::Rbf),
            approximation: Approximation::Vfe,
            inducing: InducingParams::default(),
            standardize: true,
            init: KernelInit::default(),
            noise_variance: 0.01,
            jitter: 1e-6,
            optimize: true,
            hyperopt: HyperoptParams::default(),
            seed: 0,
        }
    }
}

impl SparseGpParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field and the expected form.
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "sparse_gp".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.inducing.count == 0 {
            return bad("inducing.count", "at least 1 inducing point");
        }
        if !(self.jitter.is_finite() && self.jitter >= 0.0) {
            return bad("jitter", "a non-negative number");
        }
        self.hyperopt
            .check("sparse_gp", self.optimize, &self.init, self.noise_variance)
    }
}
