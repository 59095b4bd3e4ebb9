//! Hyperparameter learning shared by the GP regressors: maximise an
//! objective (a log marginal likelihood or a variational bound) with its
//! analytic gradient, over coordinates that are the logarithms of positive
//! hyperparameters (bounded, [`LogBounds`]) or free values (inducing
//! inputs), with a bounded projected L-BFGS ([`ProjectedLbfgs`], L-BFGS-B's
//! behaviour) or argmin's nonlinear conjugate gradient, from a start chosen
//! among scored candidates ([`starts`]) and optional seeded restarts. The
//! best point evaluated wins, by objective alone.

mod bounds;
mod negated;
mod params;
mod projected_lbfgs;
pub mod race;
pub mod recipe;
mod run;
mod solver;
pub mod starts;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

pub use bounds::LogBounds;
pub use params::{Bounds, HYPEROPT_FIELDS, HyperoptParams, moved_to_hyperopt};
pub use projected_lbfgs::ProjectedLbfgs;
pub use recipe::{HyperProblem, SearchSpace, learn};
pub use starts::StartPolicy;

use crate::RegressorError;
use run::Run;

/// The optimiser of the objective.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Optimizer {
    /// Bounded L-BFGS with L-BFGS-B's behaviour: a projected search that
    /// never leaves the bounds (default; the authors' scripts and GPy use
    /// scipy's L-BFGS-B). Its memory is
    /// [`OptimizerSettings::lbfgs_memory`].
    #[default]
    Lbfgs,
    /// Polak–Ribière nonlinear conjugate gradient with restarts (the paper's
    /// wording, §V-A); bounds act as quadratic penalties.
    ConjugateGradient,
}

/// The GP regressors' default L-BFGS memory (correction pairs).
pub const LBFGS_MEMORY: usize = 30;

/// How one optimiser run goes: [`HyperoptParams`] with the model's seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimizerSettings {
    /// Which optimiser.
    pub optimizer: Optimizer,
    /// Iteration limit per start.
    pub max_iters: u64,
    /// Extra starts from seeded perturbations of the initial point.
    pub restarts: usize,
    /// Seed of the perturbations.
    pub seed: u64,
    /// Stop when the gradient norm (normalised objective) falls below this.
    pub gradient_tolerance: f64,
    /// Stop when an iteration changes the objective by at most this
    /// fraction of its magnitude (scipy's L-BFGS-B rule,
    /// `(f_k − f_{k+1}) / max(|f_k|, |f_{k+1}|, 1) ≤ factr·ε`).
    pub relative_cost_tolerance: f64,
    /// Correction pairs the L-BFGS keeps (scipy's `maxcor`, 10 there).
    pub lbfgs_memory: usize,
}

/// The relative-decrease stopping rule of scipy's L-BFGS-B, on an objective
/// scaled by `unit` (one unit of the unscaled objective): stop when
/// `|f_k − f_{k+1}| ≤ relative · max(|f_k|, |f_{k+1}|, unit)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostTolerance {
    /// The fraction (`factr·ε` in scipy's terms; GPy's default is
    /// `1e7 · 2.2e-16 ≈ 2.2e-9`).
    pub relative: f64,
    /// The scaled value of one unit of the objective.
    pub unit: f64,
}

impl CostTolerance {
    /// Whether a step from cost `previous` to `current` is small enough to
    /// stop.
    pub fn converged(&self, previous: f64, current: f64) -> bool {
        (previous - current).abs()
            <= self.relative * previous.abs().max(current.abs()).max(self.unit)
    }
}

impl OptimizerSettings {
    /// Checks the numeric fields, naming the bad one for `regressor`.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`].
    pub fn check(&self, regressor: &str, optimize: bool) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: regressor.into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.max_iters == 0 && optimize {
            return bad("hyperopt.max_iters", "at least 1 (or `optimize: false`)");
        }
        if !(self.gradient_tolerance.is_finite() && self.gradient_tolerance > 0.0) {
            return bad("hyperopt.gradient_tolerance", "a positive number");
        }
        if !(self.relative_cost_tolerance.is_finite() && self.relative_cost_tolerance >= 0.0) {
            return bad("hyperopt.relative_cost_tolerance", "a non-negative number");
        }
        if self.lbfgs_memory == 0 {
            return bad("hyperopt.lbfgs_memory", "at least 1 correction pair");
        }
        Ok(())
    }
}

/// A differentiable objective to maximise.
pub trait Objective {
    /// The objective and its gradient at `coords` (already inside the
    /// bounds).
    ///
    /// # Errors
    /// When the objective cannot be evaluated there (e.g. a failed
    /// factorisation).
    fn evaluate(&self, coords: &[f64]) -> Result<(f64, Vec<f64>), RegressorError>;
}

/// The coordinates to optimise: where to start, their bounds, and which of
/// them the seeded restarts perturb (by one unit of standard normal noise).
#[derive(Debug, Clone, PartialEq)]
pub struct Coordinates {
    /// The initial point.
    pub start: Vec<f64>,
    /// One bound per coordinate.
    pub bounds: Vec<LogBounds>,
    /// Whether restarts perturb each coordinate.
    pub perturb: Vec<bool>,
}

/// The outcome of a maximisation.
#[derive(Debug, Clone, PartialEq)]
pub struct Maximized {
    /// The best point evaluated (inside the bounds).
    pub coords: Vec<f64>,
    /// The objective there.
    pub value: f64,
    /// Objective (+ gradient) evaluations over all starts.
    pub evaluations: usize,
    /// Optimiser iterations over all starts.
    pub iterations: u64,
    /// Best objective of each start.
    pub start_values: Vec<f64>,
}

/// Where a fit reports its optimiser's iterations (none by default); the
/// fit's result never depends on it.
#[derive(Clone, Default)]
pub struct ProgressSink(pub Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>);

impl ProgressSink {
    /// Whether the fit's progress asks to stop now
    /// ([`gpodo_traits::FitProgress::stop_requested`]).
    pub fn stop_requested(&self) -> bool {
        self.0.as_ref().is_some_and(|p| p.stop_requested())
    }
}

impl std::fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "ProgressSink(set)"
        } else {
            "ProgressSink(none)"
        })
    }
}

fn optimizer_error(settings: &OptimizerSettings, e: impl std::fmt::Display) -> RegressorError {
    RegressorError::Optimizer {
        optimizer: format!("{:?}", settings.optimizer),
        detail: e.to_string(),
    }
}

/// `log_theta` as the optimiser's coordinates on `bounds`: each clamped into
/// its bound.
fn clamped(log_theta: &[f64], bounds: &[LogBounds]) -> Vec<f64> {
    log_theta
        .iter()
        .zip(bounds)
        .map(|(c, b)| b.from_log(*c))
        .collect()
}

/// `base` with every coordinate that `perturb` marks moved by one standard
/// normal from `rng` and clamped into its bound (one draw per coordinate,
/// marked or not, so the stream does not depend on `perturb`).
fn perturbed(
    base: &[f64],
    bounds: &[LogBounds],
    perturb: &[bool],
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    base.iter()
        .zip(bounds.iter().zip(perturb))
        .map(|(c, (b, &p))| {
            let z: f64 = StandardNormal.sample(rng);
            if p { b.from_log(c + z) } else { *c }
        })
        .collect()
}

/// Maximises `objective` from `coords.start` and `settings.restarts` seeded
/// perturbations of it. `value_scale` normalises the objective (e.g.
/// `1/(n·p)` for a likelihood of `n·p` values) so that the tolerances mean
/// the same at any data size.
///
/// # Errors
/// [`RegressorError::Optimizer`], or the objective's own error, when no
/// start produced a finite objective.
pub fn maximize(
    objective: &dyn Objective,
    coords: &Coordinates,
    value_scale: f64,
    settings: &OptimizerSettings,
    progress: Option<&std::sync::Arc<dyn gpodo_traits::FitProgress>>,
) -> Result<Maximized, RegressorError> {
    let start0 = clamped(&coords.start, &coords.bounds);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut start_values = Vec::new();
    let (mut evaluations, mut iterations) = (0, 0);
    let mut last_error = None;
    for start in 0..=settings.restarts {
        let start_u = if start == 0 {
            start0.clone()
        } else {
            perturbed(&start0, &coords.bounds, &coords.perturb, &mut rng)
        };
        let mut run = match Run::start(objective, &coords.bounds, start_u, value_scale, settings) {
            Ok(run) => run,
            Err(e) => {
                last_error = Some(e);
                continue;
            }
        };
        run.advance(settings.max_iters, progress.map(|p| (p, start)));
        let out = run.finish();
        evaluations += out.evaluations;
        iterations += out.iterations;
        start_values.push(out.value);
        if best.as_ref().is_none_or(|(_, v)| out.value > *v) {
            best = Some((out.coords, out.value));
        }
    }
    let Some((coords, value)) = best else {
        return Err(
            last_error.unwrap_or_else(|| optimizer_error(settings, "no start was evaluated"))
        );
    };
    Ok(Maximized {
        coords,
        value,
        evaluations,
        iterations,
        start_values,
    })
}

#[cfg(test)]
mod tests {
    use std::cell::RefCell;

    use super::*;

    /// `−Σ (c_i − t_i)²`, with a maximum at `t`.
    struct Quadratic(Vec<f64>);

    impl Objective for Quadratic {
        fn evaluate(&self, c: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
            let value = -c
                .iter()
                .zip(&self.0)
                .map(|(c, t)| (c - t).powi(2))
                .sum::<f64>();
            let grad = c.iter().zip(&self.0).map(|(c, t)| -2.0 * (c - t)).collect();
            Ok((value, grad))
        }
    }

    /// Settings for the tests of this module and its submodules.
    pub(super) fn settings(optimizer: Optimizer) -> OptimizerSettings {
        OptimizerSettings {
            optimizer,
            max_iters: 100,
            restarts: 2,
            seed: 3,
            gradient_tolerance: 1e-10,
            relative_cost_tolerance: 0.0,
            lbfgs_memory: 10,
        }
    }

    #[test]
    fn a_memory_of_zero_pairs_is_named_in_the_error() {
        let bad = OptimizerSettings {
            lbfgs_memory: 0,
            ..settings(Optimizer::Lbfgs)
        };
        match bad.check("exact_gp", true) {
            Err(RegressorError::InvalidSpec { field, .. }) => {
                assert_eq!(field, "hyperopt.lbfgs_memory")
            }
            other => panic!("expected an InvalidSpec error, got {other:?}"),
        }
        assert!(settings(Optimizer::Lbfgs).check("exact_gp", true).is_ok());
    }

    /// [`Quadratic`], remembering every point it is evaluated at.
    struct Counting {
        inner: Quadratic,
        points: RefCell<Vec<Vec<f64>>>,
    }

    impl Objective for Counting {
        fn evaluate(&self, c: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
            self.points.borrow_mut().push(c.to_vec());
            self.inner.evaluate(c)
        }
    }

    #[test]
    fn evaluates_no_point_twice_when_the_start_sets_the_scale() {
        // The gradient at the start (norm 2·√(100² + 50²) ≈ 224) rescales
        // the objective; the start is still evaluated once.
        let objective = Counting {
            inner: Quadratic(vec![100.0, -50.0]),
            points: RefCell::new(Vec::new()),
        };
        let coords = Coordinates {
            start: vec![0.0; 2],
            bounds: vec![LogBounds::unbounded(); 2],
            perturb: vec![true; 2],
        };
        let one_start = OptimizerSettings {
            restarts: 0,
            ..settings(Optimizer::Lbfgs)
        };
        let out = maximize(&objective, &coords, 1.0, &one_start, None).unwrap();
        let points = objective.points.borrow();
        assert_eq!(out.evaluations, points.len());
        for pair in points.windows(2) {
            assert_ne!(pair[0], pair[1], "the same point evaluated twice in a row");
        }
        assert!((out.coords[0] - 100.0).abs() < 1e-6, "{out:?}");
    }

    #[test]
    fn finds_the_maximum_inside_and_stops_at_a_bound() {
        let objective = Quadratic(vec![0.5, -2.0, 3.0]);
        let coords = Coordinates {
            start: vec![0.0; 3],
            bounds: vec![
                LogBounds::unbounded(),
                LogBounds::unbounded(),
                LogBounds::new([1e-3, 1.0f64.exp()]),
            ],
            perturb: vec![true, false, true],
        };
        for optimizer in [Optimizer::Lbfgs, Optimizer::ConjugateGradient] {
            let out = maximize(&objective, &coords, 1.0, &settings(optimizer), None).unwrap();
            assert!((out.coords[0] - 0.5).abs() < 1e-6, "{out:?}");
            assert!((out.coords[1] + 2.0).abs() < 1e-6, "{out:?}");
            assert!(
                (out.coords[2] - 1.0).abs() < 1e-6,
                "bounded at log e: {out:?}"
            );
            assert!((out.value + 4.0).abs() < 1e-6);
            assert_eq!(out.start_values.len(), 3);
        }
    }
}
