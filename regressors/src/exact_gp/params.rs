//! What an exact GP is asked to do, as written in YAML
//! (`kind: exact_gp`), validated once when the configuration is read.

use serde::{Deserialize, Serialize};

use super::choice::KernelChoice;
use super::iterative::IterativeSettings;
use crate::RegressorError;
use crate::hyperopt::HyperoptParams;
use crate::kernels::{KernelExpr, KernelInit, LeafName};

/// How the output columns share hyperparameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputSharing {
    /// One kernel and one noise for all outputs, one factorisation (GPy's
    /// `GPRegression` on an `n × p` target; the authors' setting). Default.
    #[default]
    Shared,
    /// One independent GP, with its own hyperparameters, per output.
    Independent,
}

/// How the exact GP evaluates its log marginal likelihood while it learns
/// the hyperparameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// A Cholesky factor and an inverse per evaluation, `O(n³)` (default).
    #[default]
    Dense,
    /// Batched preconditioned conjugate gradients and stochastic Lanczos
    /// quadrature, `O(n²)` per iteration, no `n × n` inverse
    /// ([`super::iterative`]); the `iterative:` settings apply. The
    /// posterior of the learned model is then one Cholesky factor.
    Iterative,
    /// Dense up to [`Solver::AUTO_ITERATIVE_ABOVE_ROWS`] training rows;
    /// above, iterative, unless the noise variance learned on the
    /// iterative fit's subset is small (below 0.05 of the standardised
    /// targets' variance) and the rows are at most
    /// [`Solver::AUTO_SMALL_NOISE_DENSE_UP_TO_ROWS`]: then dense, from the
    /// subset's optimum.
    Auto,
}

impl Solver {
    /// The training rows above which `auto` considers iterative solves: at
    /// a large noise variance an iterative evaluation (rank-300
    /// preconditioner, 16 probes) is as fast as a dense one at 2000 rows and
    /// 1.8× faster at 4000, which pays for the dense fit on its subset
    /// (`cargo bench -p gpodo-regressors --bench exact_gp_solvers`;
    /// `bench/README.md`, "By iterative solves").
    pub const AUTO_ITERATIVE_ABOVE_ROWS: usize = 4000;

    /// The most training rows `auto` fits densely when the noise is small:
    /// there CG's iterations grow with `n`, and a dense evaluation stayed
    /// 1.96× (4000 rows) and 1.82× (6000) faster than an iterative one
    /// (same benchmark), a lead that shrinks too slowly to end before the
    /// dense path's memory does. 12 000 rows keep its five `n × n` matrices
    /// at 5.8 GB.
    pub const AUTO_SMALL_NOISE_DENSE_UP_TO_ROWS: usize = 12_000;

    /// Whether a fit on `n` rows may evaluate densely (and so needs the
    /// dense path's memory).
    pub fn may_be_dense(self, n: usize) -> bool {
        match self {
            Self::Dense => true,
            Self::Iterative => false,
            Self::Auto => n <= Self::AUTO_SMALL_NOISE_DENSE_UP_TO_ROWS,
        }
    }

    /// The solver a fit on `n` rows starts with: `auto` resolved by `n`
    /// alone (above its crossover it may still go dense at small noise).
    pub fn resolve(self, n: usize) -> Self {
        match self {
            Self::Auto if n > Self::AUTO_ITERATIVE_ABOVE_ROWS => Self::Iterative,
            Self::Auto => Self::Dense,
            other => other,
        }
    }
}

/// Exact GP settings. Every field has a default; see `experiments/README.md`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExactGpParams {
    /// Kernel expression (default `rbf`), e.g. `rbf + linear`; or `auto`,
    /// which fits each of `kernel_candidates` and keeps the highest log
    /// marginal likelihood.
    pub kernel: KernelChoice,
    /// The kernels `kernel: auto` tries (default: rbf, matern52, rbf +
    /// linear, matern52 + linear).
    pub kernel_candidates: Vec<KernelExpr>,
    /// Output sharing (default `shared`).
    pub outputs: OutputSharing,
    /// Z-score inputs and outputs with training statistics (default true);
    /// predictions are mapped back (variance × std²).
    pub standardize: bool,
    /// Initial kernel hyperparameters. Setting `init.lengthscale` replaces
    /// the candidate lengthscales of the start policy by that one value.
    pub init: KernelInit,
    /// Initial noise variance in standardised units (default 0.01, the
    /// authors' `0.01·var(Y)`).
    pub noise_variance: f64,
    /// Learn the hyperparameters (default true); false keeps the initial ones.
    pub optimize: bool,
    /// How the hyperparameters are learned.
    pub hyperopt: HyperoptParams,
    /// Seed of the candidate and restart perturbations (default 0).
    pub seed: u64,
    /// How the likelihood is evaluated while learning (default `dense`).
    pub solver: Solver,
    /// The iterative solver's settings (read with `solver: iterative`, or
    /// `auto` above its crossover).
    pub iterative: IterativeSettings,
}

impl Default for ExactGpParams {
    fn default() -> Self {
        Self {
            kernel: KernelChoice::default(),
            kernel_candidates: KernelChoice::default_candidates(),
            outputs: OutputSharing::Shared,
            standardize: true,
            init: KernelInit::default(),
            noise_variance: 0.01,
            optimize: true,
            hyperopt: HyperoptParams::default(),
            seed: 0,
            solver: Solver::Dense,
            iterative: IterativeSettings::default(),
        }
    }
}

impl ExactGpParams {
    /// Parameters with the given kernel expression and defaults elsewhere.
    pub fn with_kernel(kernel: KernelExpr) -> Self {
        Self {
            kernel: KernelChoice::Expr(kernel),
            ..Self::default()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field and the expected form.
    pub fn check(&self) -> Result<(), RegressorError> {
        if self.kernel == KernelChoice::Auto {
            if self.kernel_candidates.is_empty() {
                return Err(RegressorError::InvalidSpec {
                    regressor: "exact_gp".into(),
                    field: "kernel_candidates".into(),
                    expected: "at least one kernel for `kernel: auto` to try".into(),
                });
            }
            if !self.optimize {
                return Err(RegressorError::InvalidSpec {
                    regressor: "exact_gp".into(),
                    field: "kernel".into(),
                    expected: "a kernel expression when `optimize: false` (`auto` compares learned kernels)".into(),
                });
            }
        }
        self.iterative.check()?;
        self.hyperopt
            .check("exact_gp", self.optimize, &self.init, self.noise_variance)
    }

    /// The kernel expression to fit: the one given, or for `auto` the
    /// first candidate (each candidate's fit sets its own).
    pub fn kernel_expr(&self) -> KernelExpr {
        match &self.kernel {
            KernelChoice::Expr(e) => e.clone(),
            KernelChoice::Auto => self
                .kernel_candidates
                .first()
                .cloned()
                .unwrap_or(KernelExpr::Leaf(LeafName::Rbf)),
        }
    }
}
