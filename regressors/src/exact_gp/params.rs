//! What an exact GP is asked to do, as written in YAML
//! (`kind: exact_gp`), validated once when the configuration is read.

use serde::{Deserialize, Serialize};

use crate::RegressorError;
pub use crate::hyperopt::Optimizer;
use crate::hyperopt::{LBFGS_MEMORY, OptimizerSettings, StartPolicy};
use crate::kernels::{KernelExpr, KernelInit, LeafName, ParamKind};

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

/// `[lower, upper]` bounds of each kind of hyperparameter, in the units of
/// the standardised data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Bounds {
    /// Signal variances (default `[1e-6, 1e4]`).
    pub variance: [f64; 2],
    /// Lengthscales (default `[1e-3, 1e5]`).
    pub lengthscale: [f64; 2],
    /// Per-input variances of the linear kernel (default `[1e-8, 1e4]`).
    pub linear_variance: [f64; 2],
    /// Noise variance (default `[1e-8, 1e2]`).
    pub noise_variance: [f64; 2],
    /// The rational quadratic's power `α` (default `[1e-3, 1e4]`).
    pub power: [f64; 2],
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            variance: [1e-6, 1e4],
            lengthscale: [1e-3, 1e5],
            linear_variance: [1e-8, 1e4],
            noise_variance: [1e-8, 1e2],
            power: [1e-3, 1e4],
        }
    }
}

fn invalid(regressor: &str, field: &str, expected: &str) -> RegressorError {
    RegressorError::InvalidSpec {
        regressor: regressor.into(),
        field: field.into(),
        expected: expected.into(),
    }
}

impl Bounds {
    /// Checks that every bound is `[lower, upper]` with `0 < lower < upper`.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bound, for `regressor`.
    pub fn check(&self, regressor: &str) -> Result<(), RegressorError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let bounds = [
            ("bounds.variance", self.variance),
            ("bounds.lengthscale", self.lengthscale),
            ("bounds.linear_variance", self.linear_variance),
            ("bounds.noise_variance", self.noise_variance),
            ("bounds.power", self.power),
        ];
        for (field, [lo, hi]) in bounds {
            if !(positive(lo) && positive(hi) && lo < hi) {
                return Err(invalid(
                    regressor,
                    field,
                    "[lower, upper] with 0 < lower < upper",
                ));
            }
        }
        Ok(())
    }

    /// Checks that the initial kernel hyperparameters are within the bounds.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the `init.*` field.
    pub fn check_init(&self, init: &KernelInit, regressor: &str) -> Result<(), RegressorError> {
        let within = |v: f64, [lo, hi]: [f64; 2]| v >= lo && v <= hi;
        let checks = [
            (
                "init.variance",
                Some(init.variance),
                self.variance,
                "variance",
            ),
            (
                "init.white_variance",
                Some(init.white_variance),
                self.variance,
                "variance",
            ),
            (
                "init.lengthscale",
                init.lengthscale,
                self.lengthscale,
                "lengthscale",
            ),
            (
                "init.linear_variance",
                init.linear_variance,
                self.linear_variance,
                "linear_variance",
            ),
            ("init.power", Some(init.power), self.power, "power"),
        ];
        for (field, value, range, bound) in checks {
            if let Some(v) = value
                && !within(v, range)
            {
                return Err(invalid(
                    regressor,
                    field,
                    &format!("a positive value within bounds.{bound}"),
                ));
            }
        }
        Ok(())
    }

    /// The bounds of a kernel hyperparameter of this kind.
    pub fn of(&self, kind: ParamKind) -> [f64; 2] {
        match kind {
            ParamKind::Variance => self.variance,
            ParamKind::Lengthscale => self.lengthscale,
            ParamKind::LinearVariance => self.linear_variance,
            ParamKind::Power => self.power,
        }
    }
}

/// Exact GP settings. Every field has a default; see `experiments/README.md`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExactGpParams {
    /// Kernel expression (default `rbf`), e.g. `rbf + linear`.
    pub kernel: KernelExpr,
    /// Output sharing (default `shared`).
    pub outputs: OutputSharing,
    /// Z-score inputs and outputs with training statistics (default true);
    /// predictions are mapped back (variance × std²).
    pub standardize: bool,
    /// Initial kernel hyperparameters. Setting `init.lengthscale` replaces
    /// the candidate lengthscales of the start policy by that one value.
    pub init: KernelInit,
    /// How the optimiser's start is chosen: candidate starts (lengthscale
    /// 1, `√D`, the median input distance, seeded perturbations of each)
    /// scored by their log marginal likelihood, the optimiser run from the
    /// best few (default: 2 perturbations each, the best 2 optimised).
    pub start: StartPolicy,
    /// Initial noise variance in standardised units (default 0.01, the
    /// authors' `0.01·var(Y)`).
    pub noise_variance: f64,
    /// Learn the hyperparameters (default true); false keeps the initial ones.
    pub optimize: bool,
    /// Optimiser (default `lbfgs`).
    pub optimizer: Optimizer,
    /// Iteration limit per start (default 200).
    pub max_iters: u64,
    /// Extra optimiser runs from seeded random perturbations of the best
    /// candidate start (default 0); the best log marginal likelihood wins.
    pub restarts: usize,
    /// Seed of the candidate and restart perturbations (default 0).
    pub seed: u64,
    /// Stop when the norm of the gradient of the mean log likelihood per
    /// target value (in the optimiser's coordinates) falls below this
    /// (default 1e-5).
    pub gradient_tolerance: f64,
    /// Stop when an iteration changes the objective by at most this
    /// fraction of its magnitude (default 2.2e-9: scipy's L-BFGS-B rule
    /// with GPy's `factr = 1e7`, see [`crate::hyperopt::CostTolerance`]).
    pub relative_cost_tolerance: f64,
    /// Correction pairs of the L-BFGS (default 30; scipy's and so GPy's
    /// `maxcor` is 10). With 30 to 60 log-hyperparameters, 10 pairs see
    /// too little of the curvature (measured in `bench/README.md`, "L-BFGS
    /// memory").
    pub lbfgs_memory: usize,
    /// Hyperparameter bounds.
    pub bounds: Bounds,
}

impl Default for ExactGpParams {
    fn default() -> Self {
        Self {
            kernel: KernelExpr::Leaf(LeafName::Rbf),
            outputs: OutputSharing::Shared,
            standardize: true,
            init: KernelInit::default(),
            start: StartPolicy::default(),
            noise_variance: 0.01,
            optimize: true,
            optimizer: Optimizer::Lbfgs,
            max_iters: 200,
            restarts: 0,
            seed: 0,
            gradient_tolerance: 1e-5,
            relative_cost_tolerance: 2.2e-9,
            lbfgs_memory: LBFGS_MEMORY,
            bounds: Bounds::default(),
        }
    }
}

impl ExactGpParams {
    /// Parameters with the given kernel expression and defaults elsewhere.
    pub fn with_kernel(kernel: KernelExpr) -> Self {
        Self {
            kernel,
            ..Self::default()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field and the expected form.
    pub fn check(&self) -> Result<(), RegressorError> {
        self.bounds.check("exact_gp")?;
        let [lo, hi] = self.bounds.noise_variance;
        if !(self.noise_variance >= lo && self.noise_variance <= hi) {
            return Err(invalid(
                "exact_gp",
                "noise_variance",
                "a positive variance within bounds.noise_variance",
            ));
        }
        self.bounds.check_init(&self.init, "exact_gp")?;
        self.start.check("exact_gp")?;
        self.settings().check("exact_gp", self.optimize)
    }

    /// The optimiser settings.
    pub fn settings(&self) -> OptimizerSettings {
        OptimizerSettings {
            optimizer: self.optimizer,
            max_iters: self.max_iters,
            restarts: self.restarts,
            seed: self.seed,
            gradient_tolerance: self.gradient_tolerance,
            relative_cost_tolerance: self.relative_cost_tolerance,
            lbfgs_memory: self.lbfgs_memory,
        }
    }
}
