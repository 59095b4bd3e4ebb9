//! Hyperparameter learning: maximise the log marginal likelihood with its
//! analytic gradient, in log space with the bounds of [`LogBounds`], with
//! argmin's L-BFGS or nonlinear conjugate gradient (Moré–Thuente line
//! search), from the initial hyperparameters and optional seeded restarts.

use std::cell::{Cell, RefCell};

use argmin::core::{
    CostFunction, Error as ArgminError, Executor, Gradient, IterState, KV, Problem, Solver, State,
    TerminationReason, TerminationStatus,
};
use argmin::solver::conjugategradient::NonlinearConjugateGradient;
use argmin::solver::conjugategradient::beta::PolakRibiere;
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use faer::MatRef;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::likelihood::log_marginal_likelihood;
use super::params::{ExactGpParams, Optimizer};
use super::transform::LogBounds;
use crate::RegressorError;
use crate::kernels::Kernel;

/// The outcome of hyperparameter learning.
#[derive(Debug, Clone, PartialEq)]
pub struct Optimized {
    /// The kernel with the learned hyperparameters.
    pub kernel: Kernel,
    /// The learned noise variance.
    pub noise_variance: f64,
    /// The log marginal likelihood there.
    pub lml: f64,
    /// Objective (+ gradient) evaluations over all starts.
    pub evaluations: usize,
    /// Optimiser iterations over all starts.
    pub iterations: u64,
    /// Best log marginal likelihood of each start.
    pub start_lml: Vec<f64>,
}

/// A point, the cost there and its gradient.
type Evaluated = (Vec<f64>, f64, Vec<f64>);

/// The negative LML in the optimiser's coordinates, caching the last point
/// (argmin asks for the cost and the gradient separately) and remembering
/// the best point evaluated.
struct NegativeLml<'a> {
    template: Kernel,
    transforms: Vec<LogBounds>,
    x: MatRef<'a, f64>,
    y: MatRef<'a, f64>,
    /// Objective scale: `1/(n·p)`, further divided by the gradient norm at
    /// the start when that exceeds 1, so that the optimiser's first step
    /// (along the raw gradient) is at most about one unit of `log θ`, as
    /// L-BFGS-B's first step is — whatever the data size.
    scale: Cell<f64>,
    last: RefCell<Option<Evaluated>>,
    best: &'a RefCell<Option<(Vec<f64>, f64)>>,
    evaluations: &'a Cell<usize>,
}

/// What a start leaves behind, even when the optimiser stops with an error.
#[derive(Default)]
struct StartRecord {
    best: RefCell<Option<(Vec<f64>, f64)>>,
    evaluations: Cell<usize>,
}

impl NegativeLml<'_> {
    fn hyperparameters(&self, u: &[f64]) -> (Kernel, f64) {
        let log_theta: Vec<f64> = u
            .iter()
            .zip(&self.transforms)
            .map(|(u, t)| t.to_log(*u))
            .collect();
        let m = log_theta.len() - 1;
        let mut kernel = self.template.clone();
        kernel.set_log_params(&log_theta[..m]);
        (kernel, log_theta[m].exp())
    }

    fn evaluate(&self, u: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        if let Some((at, cost, grad)) = self.last.borrow().as_ref()
            && at.as_slice() == u
        {
            return Ok((*cost, grad.clone()));
        }
        let (kernel, noise) = self.hyperparameters(u);
        let eval = log_marginal_likelihood(&kernel, noise, self.x, self.y, true)?;
        self.evaluations.set(self.evaluations.get() + 1);
        tracing::trace!(
            evaluation = self.evaluations.get(),
            lml = eval.lml,
            "exact GP objective"
        );
        let likelihood_cost = -eval.lml * self.scale.get();
        let mut cost = likelihood_cost;
        let mut grad: Vec<f64> = eval
            .gradient
            .unwrap_or_default()
            .iter()
            .zip(u.iter().zip(&self.transforms))
            .map(|(g, (u, t))| -g * t.derivative(*u) * self.scale.get())
            .collect();
        for ((g, u), t) in grad.iter_mut().zip(u).zip(&self.transforms) {
            let (p, dp) = t.penalty(*u);
            cost += p;
            *g += dp;
        }
        // The best point is kept by likelihood alone, at its clamped
        // coordinates (where the hyperparameters were evaluated).
        let improved = self
            .best
            .borrow()
            .as_ref()
            .is_none_or(|(_, c)| likelihood_cost < *c);
        if improved {
            let clamped = u
                .iter()
                .zip(&self.transforms)
                .map(|(u, t)| t.to_log(*u))
                .collect();
            *self.best.borrow_mut() = Some((clamped, likelihood_cost));
        }
        *self.last.borrow_mut() = Some((u.to_vec(), cost, grad.clone()));
        Ok((cost, grad))
    }
}

impl CostFunction for NegativeLml<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, ArgminError> {
        Ok(self.evaluate(u)?.0)
    }
}

impl Gradient for NegativeLml<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Self::Param) -> Result<Vec<f64>, ArgminError> {
        Ok(self.evaluate(u)?.1)
    }
}

type GpState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// Adds gradient-norm and cost-change stopping to a solver that has none
/// (argmin's nonlinear CG runs to its iteration limit otherwise).
struct Converging<S> {
    inner: S,
    tol_grad: f64,
    tol_cost: f64,
}

impl<O, S: Solver<O, GpState>> Solver<O, GpState> for Converging<S> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: GpState,
    ) -> Result<(GpState, Option<KV>), ArgminError> {
        self.inner.init(problem, state)
    }
    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: GpState,
    ) -> Result<(GpState, Option<KV>), ArgminError> {
        self.inner.next_iter(problem, state)
    }
    fn terminate(&mut self, state: &GpState) -> TerminationStatus {
        let status = self.inner.terminate(state);
        if status.terminated() {
            return status;
        }
        if let Some(g) = state.get_gradient()
            && g.iter().map(|v| v * v).sum::<f64>().sqrt() < self.tol_grad
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        if state.get_iter() > 0 && (state.get_prev_cost() - state.get_cost()).abs() < self.tol_cost
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

fn optimizer_error(params: &ExactGpParams, e: impl std::fmt::Display) -> RegressorError {
    RegressorError::Optimizer {
        optimizer: format!("{:?}", params.optimizer),
        detail: e.to_string(),
    }
}

/// Runs one start from `u0`; returns the best point seen and the iterations.
fn run_start(
    problem: NegativeLml<'_>,
    u0: Vec<f64>,
    params: &ExactGpParams,
    tol_cost: f64,
) -> Result<u64, RegressorError> {
    let record_has_best = problem.best.borrow().is_some();
    let line_search = MoreThuenteLineSearch::new();
    fn converging<S>(inner: S, params: &ExactGpParams, tol_cost: f64) -> Converging<S> {
        Converging {
            inner,
            tol_grad: params.gradient_tolerance,
            tol_cost,
        }
    }
    let iterations = match params.optimizer {
        Optimizer::Lbfgs => {
            let solver = LBFGS::new(line_search, 10)
                .with_tolerance_grad(params.gradient_tolerance)
                .and_then(|s| s.with_tolerance_cost(tol_cost))
                .map_err(|e| optimizer_error(params, e))?;
            Executor::new(problem, converging(solver, params, tol_cost))
                .configure(|s| s.param(u0).max_iters(params.max_iters))
                .run()
                .map(|r| r.state().get_iter())
        }
        Optimizer::ConjugateGradient => {
            let line_search = line_search
                .with_c(1e-4, 0.1)
                .map_err(|e| optimizer_error(params, e))?;
            let solver = NonlinearConjugateGradient::new(line_search, PolakRibiere::new())
                .restart_iters(u0.len() as u64)
                .restart_orthogonality(0.1);
            Executor::new(problem, converging(solver, params, tol_cost))
                .configure(|s| s.param(u0).max_iters(params.max_iters))
                .run()
                .map(|r| r.state().get_iter())
        }
    };
    // A failed line search still leaves the best point evaluated, which is
    // what we keep; only a start that evaluated nothing is an error.
    match iterations {
        Ok(n) => Ok(n),
        Err(e) if record_has_best => {
            tracing::debug!(error = %e, "optimiser stopped early; keeping the best point");
            Ok(0)
        }
        Err(e) => Err(optimizer_error(params, e)),
    }
}

/// Learns the kernel hyperparameters and noise variance of `kernel` on
/// `(x, y)` by maximising the log marginal likelihood.
///
/// # Errors
/// [`RegressorError::Optimizer`] or [`RegressorError::NotPositiveDefinite`]
/// when no start produced a finite objective.
pub fn maximize_lml(
    kernel: &Kernel,
    noise_variance: f64,
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    params: &ExactGpParams,
) -> Result<Optimized, RegressorError> {
    let mut transforms: Vec<LogBounds> = kernel
        .param_kinds()
        .into_iter()
        .map(|k| LogBounds::new(params.bounds.of(k)))
        .collect();
    transforms.push(LogBounds::new(params.bounds.noise_variance));
    let mut log_theta0 = kernel.log_params();
    log_theta0.push(noise_variance.ln());
    let u0: Vec<f64> = log_theta0
        .iter()
        .zip(&transforms)
        .map(|(l, t)| t.from_log(*l))
        .collect();

    let per_value = 1.0 / (y.nrows() * y.ncols()).max(1) as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut start_lml = Vec::new();
    let (mut evaluations, mut iterations) = (0, 0);
    let mut last_error = None;
    for start in 0..=params.restarts {
        let start_u: Vec<f64> = if start == 0 {
            u0.clone()
        } else {
            // One unit of log-space noise per hyperparameter around the start.
            log_theta0
                .iter()
                .zip(&transforms)
                .map(|(l, t)| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    t.from_log(l + z)
                })
                .collect()
        };
        let record = StartRecord::default();
        let problem = NegativeLml {
            template: kernel.clone(),
            transforms: transforms.clone(),
            x,
            y,
            scale: Cell::new(per_value),
            last: RefCell::new(None),
            best: &record.best,
            evaluations: &record.evaluations,
        };
        let initial = match problem.evaluate(&start_u) {
            Ok((_, grad)) => {
                let norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
                if norm > 1.0 {
                    problem.scale.set(per_value / norm);
                    *problem.last.borrow_mut() = None;
                    *record.best.borrow_mut() = None;
                }
                match problem.evaluate(&start_u) {
                    Ok((cost, _)) => cost,
                    Err(e) => {
                        last_error = Some(e);
                        continue;
                    }
                }
            }
            Err(e) => {
                last_error = Some(e);
                continue;
            }
        };
        let scale = problem.scale.get();
        let tol_cost = params.relative_cost_tolerance * initial.abs().max(1.0);
        match run_start(problem, start_u, params, tol_cost) {
            Ok(n) => iterations += n,
            Err(e) => last_error = Some(e),
        }
        evaluations += record.evaluations.get();
        if let Some((u, cost)) = record.best.into_inner() {
            // The best point is inside the bounds (no penalty there).
            let lml = -cost / scale;
            start_lml.push(lml);
            if best.as_ref().is_none_or(|(_, l)| lml > *l) {
                best = Some((u, lml));
            }
        }
    }
    let Some((u, lml)) = best else {
        return Err(last_error.unwrap_or_else(|| optimizer_error(params, "no start was evaluated")));
    };
    let record = StartRecord::default();
    let problem = NegativeLml {
        template: kernel.clone(),
        transforms,
        x,
        y,
        scale: Cell::new(per_value),
        last: RefCell::new(None),
        best: &record.best,
        evaluations: &record.evaluations,
    };
    let (kernel, noise_variance) = problem.hyperparameters(&u);
    Ok(Optimized {
        kernel,
        noise_variance,
        lml,
        evaluations,
        iterations,
        start_lml,
    })
}
