//! The hyperparameter-learning settings both GPs share, as written in YAML
//! in a model's `hyperopt:` block: which optimiser, how it starts, when it
//! stops, and within which bounds it searches. Validated once when the
//! configuration is read.

use serde::{Deserialize, Serialize};

use super::{LBFGS_MEMORY, Optimizer, OptimizerSettings, StartPolicy};
use crate::RegressorError;
use crate::kernels::{KernelInit, ParamKind};

/// The settings that live in a GP's `hyperopt:` block; a configuration
/// that sets one of them beside `kernel` is told where it belongs
/// ([`moved_to_hyperopt`]).
pub const HYPEROPT_FIELDS: [&str; 8] = [
    "optimizer",
    "max_iters",
    "start",
    "restarts",
    "gradient_tolerance",
    "relative_cost_tolerance",
    "lbfgs_memory",
    "bounds",
];

/// Where a GP setting written at the model's top level belongs now, when it
/// is one of the `hyperopt:` settings: `max_iters` → `hyperopt.max_iters`.
pub fn moved_to_hyperopt(key: &str) -> Option<String> {
    HYPEROPT_FIELDS
        .contains(&key)
        .then(|| format!("hyperopt.{key}"))
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
            ("hyperopt.bounds.variance", self.variance),
            ("hyperopt.bounds.lengthscale", self.lengthscale),
            ("hyperopt.bounds.linear_variance", self.linear_variance),
            ("hyperopt.bounds.noise_variance", self.noise_variance),
            ("hyperopt.bounds.power", self.power),
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
                    &format!("a positive value within hyperopt.bounds.{bound}"),
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

/// How a GP learns its hyperparameters (the `hyperopt:` block of
/// `exact_gp` and `sparse_gp`). Every field has a default.
///
/// Two knobs add starts, at different moments: `start.perturbations`
/// adds candidates that are only scored (one objective evaluation each)
/// before the race picks a leader, while `restarts` adds whole optimiser
/// runs from perturbations of the leader's optimum, after the race.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HyperoptParams {
    /// Optimiser (default `lbfgs`).
    pub optimizer: Optimizer,
    /// Iteration limit per optimiser run (default 200).
    pub max_iters: u64,
    /// How the optimiser's start is chosen: candidate starts (lengthscale
    /// 1, `√D`, the median input distance, seeded perturbations of each)
    /// scored by the objective, the optimiser raced from the named bases
    /// and the best few, the leader run to convergence.
    pub start: StartPolicy,
    /// Extra optimiser runs from seeded perturbations of the race's leader
    /// (default 0); the best objective wins.
    pub restarts: usize,
    /// Stop when the norm of the gradient of the objective per target
    /// value (in the optimiser's coordinates) falls below this (default
    /// 1e-5).
    pub gradient_tolerance: f64,
    /// Stop when an iteration changes the objective by at most this
    /// fraction of its magnitude (default 2.2e-9: scipy's L-BFGS-B rule
    /// with GPy's `factr = 1e7`, see [`super::CostTolerance`]).
    pub relative_cost_tolerance: f64,
    /// Correction pairs of the L-BFGS (default 30; scipy's and so GPy's
    /// `maxcor` is 10, which sees too little of the curvature of 30 to 60
    /// log-hyperparameters; `bench/README.md`, "L-BFGS memory").
    pub lbfgs_memory: usize,
    /// Where the hyperparameters may go.
    pub bounds: Bounds,
}

impl Default for HyperoptParams {
    fn default() -> Self {
        Self {
            optimizer: Optimizer::Lbfgs,
            max_iters: 200,
            start: StartPolicy::default(),
            restarts: 0,
            gradient_tolerance: 1e-5,
            relative_cost_tolerance: 2.2e-9,
            lbfgs_memory: LBFGS_MEMORY,
            bounds: Bounds::default(),
        }
    }
}

impl HyperoptParams {
    /// Checks every field for `regressor`, and that its initial
    /// hyperparameters (`init`, `noise_variance`) lie within the bounds.
    /// `optimize` is whether the model learns at all (an iteration limit
    /// of 0 is then an error).
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field.
    pub fn check(
        &self,
        regressor: &str,
        optimize: bool,
        init: &KernelInit,
        noise_variance: f64,
    ) -> Result<(), RegressorError> {
        self.bounds.check(regressor)?;
        let [lo, hi] = self.bounds.noise_variance;
        if !(noise_variance >= lo && noise_variance <= hi) {
            return Err(invalid(
                regressor,
                "noise_variance",
                "a positive variance within hyperopt.bounds.noise_variance",
            ));
        }
        self.bounds.check_init(init, regressor)?;
        self.start.check(regressor)?;
        self.settings(0).check(regressor, optimize)
    }

    /// The optimiser settings of one fit, with the model's `seed`.
    pub fn settings(&self, seed: u64) -> OptimizerSettings {
        OptimizerSettings {
            optimizer: self.optimizer,
            max_iters: self.max_iters,
            restarts: self.restarts,
            seed,
            gradient_tolerance: self.gradient_tolerance,
            relative_cost_tolerance: self.relative_cost_tolerance,
            lbfgs_memory: self.lbfgs_memory,
        }
    }
}
