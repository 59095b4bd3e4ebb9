//! Hyperparameter learning shared by the GP regressors: maximise an
//! objective (a log marginal likelihood or a variational bound) with its
//! analytic gradient, over coordinates that are the logarithms of positive
//! hyperparameters (bounded, [`LogBounds`]) or free values (inducing
//! inputs), with a bounded projected L-BFGS ([`ProjectedLbfgs`], L-BFGS-B's
//! behaviour) or argmin's nonlinear conjugate gradient, from a start chosen
//! among scored candidates ([`starts`]) and optional seeded restarts. The
//! best point evaluated wins, by objective alone.

mod bounds;
mod projected_lbfgs;
mod run;
mod solver;
pub mod starts;

use std::cell::{Cell, RefCell};

use argmin::core::{CostFunction, Error as ArgminError, Gradient};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

pub use bounds::LogBounds;
pub use projected_lbfgs::ProjectedLbfgs;
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

/// How to run the optimiser (the flat YAML fields of each GP's parameters).
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
            return bad("max_iters", "at least 1 (or `optimize: false`)");
        }
        if !(self.gradient_tolerance.is_finite() && self.gradient_tolerance > 0.0) {
            return bad("gradient_tolerance", "a positive number");
        }
        if !(self.relative_cost_tolerance.is_finite() && self.relative_cost_tolerance >= 0.0) {
            return bad("relative_cost_tolerance", "a non-negative number");
        }
        if self.lbfgs_memory == 0 {
            return bad("lbfgs_memory", "at least 1 correction pair");
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

impl std::fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "ProgressSink(set)"
        } else {
            "ProgressSink(none)"
        })
    }
}

/// A point, the cost there and its gradient.
type Evaluated = (Vec<f64>, f64, Vec<f64>);

/// One evaluation of the objective, before negation and scaling.
struct RawEvaluation {
    /// Where it was evaluated (the optimiser's point, clamped).
    clamped: Vec<f64>,
    value: f64,
    gradient: Vec<f64>,
}

/// The negated, scaled objective in the optimiser's (unclamped)
/// coordinates, caching the last point (argmin asks for the cost and the
/// gradient separately) and remembering the best point evaluated.
struct Negated<'a> {
    objective: &'a dyn Objective,
    bounds: &'a [LogBounds],
    /// Objective scale: `value_scale` (e.g. `1/(n·p)`), further divided by
    /// the gradient norm at the start when that exceeds 1, so that the
    /// optimiser's first step (along the raw gradient) is at most about one
    /// unit of `log θ`, as L-BFGS-B's first step is — whatever the data size.
    scale: Cell<f64>,
    last: RefCell<Option<Evaluated>>,
    best: RefCell<Option<(Vec<f64>, f64)>>,
    evaluations: Cell<usize>,
}

impl Negated<'_> {
    fn clamp(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(self.bounds)
            .map(|(u, b)| b.to_log(*u))
            .collect()
    }

    fn evaluate(&self, u: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        if let Some((at, cost, grad)) = self.last.borrow().as_ref()
            && at.as_slice() == u
        {
            return Ok((*cost, grad.clone()));
        }
        let raw = self.evaluate_raw(u)?;
        Ok(self.record(u, raw))
    }

    /// The objective and its gradient at the clamped `u`, unscaled and not
    /// cached (but counted).
    fn evaluate_raw(&self, u: &[f64]) -> Result<RawEvaluation, RegressorError> {
        let clamped = self.clamp(u);
        let (value, gradient) = self.objective.evaluate(&clamped)?;
        self.evaluations.set(self.evaluations.get() + 1);
        tracing::trace!(
            evaluation = self.evaluations.get(),
            value,
            "hyperparameter objective"
        );
        Ok(RawEvaluation {
            clamped,
            value,
            gradient,
        })
    }

    /// The cost and gradient the optimiser sees at `u` (negated, scaled,
    /// plus the bound penalties) for the objective's `raw` evaluation.
    fn scaled(&self, u: &[f64], raw: &RawEvaluation) -> (f64, f64, Vec<f64>) {
        let scale = self.scale.get();
        let objective_cost = -raw.value * scale;
        let mut cost = objective_cost;
        let mut grad: Vec<f64> = raw
            .gradient
            .iter()
            .zip(u.iter().zip(self.bounds))
            .map(|(g, (u, b))| -g * b.derivative(*u) * scale)
            .collect();
        for ((g, u), b) in grad.iter_mut().zip(u).zip(self.bounds) {
            let (p, dp) = b.penalty(*u);
            cost += p;
            *g += dp;
        }
        (objective_cost, cost, grad)
    }

    /// Scales `raw` (at `u`), caches it as the last point and keeps it as
    /// the best when it is.
    fn record(&self, u: &[f64], raw: RawEvaluation) -> (f64, Vec<f64>) {
        let (objective_cost, cost, grad) = self.scaled(u, &raw);
        // The best point is kept by objective alone, at its clamped
        // coordinates (where the objective was evaluated).
        let improved = self
            .best
            .borrow()
            .as_ref()
            .is_none_or(|(_, c)| objective_cost < *c);
        if improved {
            *self.best.borrow_mut() = Some((raw.clamped, objective_cost));
        }
        *self.last.borrow_mut() = Some((u.to_vec(), cost, grad.clone()));
        (cost, grad)
    }
}

impl CostFunction for &Negated<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, ArgminError> {
        Ok(self.evaluate(u)?.0)
    }
}

impl Gradient for &Negated<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Self::Param) -> Result<Vec<f64>, ArgminError> {
        Ok(self.evaluate(u)?.1)
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
            Err(RegressorError::InvalidSpec { field, .. }) => assert_eq!(field, "lbfgs_memory"),
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
