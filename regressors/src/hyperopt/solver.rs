//! One optimiser start with argmin: the bounded projected L-BFGS
//! ([`ProjectedLbfgs`], L-BFGS-B's behaviour) or Polak–Ribière nonlinear
//! conjugate gradient (Moré–Thuente line search, bounds as penalties), with
//! the same stopping rules (gradient norm, change of the objective), as a
//! [`Stepper`] that can pause at an iteration limit and resume.

use std::sync::Arc;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    Error as ArgminError, Executor, IterState, KV, Problem, Solver, State, TerminationReason,
    TerminationStatus,
};
use argmin::solver::conjugategradient::NonlinearConjugateGradient;
use argmin::solver::conjugategradient::beta::PolakRibiere;
use argmin::solver::linesearch::MoreThuenteLineSearch;
use gpodo_traits::FitProgress;

use super::negated::Negated;
use super::projected_lbfgs::ProjectedLbfgs;
use super::{CostTolerance, LogBounds, Optimizer, OptimizerSettings};

type HyperState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// Adds gradient-norm and cost-change stopping to a solver that has none
/// (argmin's nonlinear CG runs to its iteration limit otherwise).
struct Converging<S> {
    inner: S,
    tol_grad: f64,
    tol_cost: CostTolerance,
}

impl<O, S: Solver<O, HyperState>> Solver<O, HyperState> for Converging<S> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: HyperState,
    ) -> Result<(HyperState, Option<KV>), ArgminError> {
        self.inner.init(problem, state)
    }
    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: HyperState,
    ) -> Result<(HyperState, Option<KV>), ArgminError> {
        self.inner.next_iter(problem, state)
    }
    fn terminate(&mut self, state: &HyperState) -> TerminationStatus {
        let status = self.inner.terminate(state);
        if status.terminated() {
            return status;
        }
        if let Some(g) = state.get_gradient()
            && g.iter().map(|v| v * v).sum::<f64>().sqrt() < self.tol_grad
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        if state.get_iter() > 0
            && self
                .tol_cost
                .converged(state.get_prev_cost(), state.get_cost())
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

/// Reports each iteration to a [`FitProgress`] (an argmin observer), as
/// the objective to maximise: `−cost / scale`; when the progress asks to
/// stop, ends the run with an error.
struct Reporter {
    progress: Arc<dyn FitProgress>,
    start: usize,
    scale: f64,
}

impl Observe<HyperState> for Reporter {
    fn observe_iter(&mut self, state: &HyperState, _kv: &KV) -> Result<(), ArgminError> {
        match self.progress.iteration(
            self.start,
            state.get_iter(),
            -state.get_best_cost() / self.scale,
        ) {
            std::ops::ControlFlow::Continue(()) => Ok(()),
            std::ops::ControlFlow::Break(()) => Err(ArgminError::msg("the fit was stopped")),
        }
    }
}

/// Argmin's nonlinear CG as this module configures it.
type ConvergingCg = Converging<
    NonlinearConjugateGradient<
        Vec<f64>,
        MoreThuenteLineSearch<Vec<f64>, Vec<f64>, f64>,
        PolakRibiere,
        f64,
    >,
>;

/// The solver of one start.
enum AnySolver {
    Lbfgs(ProjectedLbfgs),
    Cg(Box<ConvergingCg>),
}

/// One start's solver with its iteration state: it runs to an iteration
/// limit, and when it stopped there it can be resumed with a higher limit
/// exactly where it was (the same iterates, the same L-BFGS memory), so a
/// run advanced in several legs is the run advanced in one.
pub(super) struct Stepper {
    solver: AnySolver,
    state: HyperState,
}

impl Stepper {
    /// A solver for `settings.optimizer` on `bounds`, to start at `u0`.
    ///
    /// # Errors
    /// When the line search cannot be configured.
    pub(super) fn new(
        bounds: &[LogBounds],
        u0: Vec<f64>,
        settings: &OptimizerSettings,
        tol_cost: CostTolerance,
    ) -> Result<Self, ArgminError> {
        let solver = match settings.optimizer {
            Optimizer::Lbfgs => AnySolver::Lbfgs(ProjectedLbfgs::new(
                bounds.iter().map(LogBounds::lower).collect(),
                bounds.iter().map(LogBounds::upper).collect(),
                settings.lbfgs_memory,
                settings.gradient_tolerance,
                tol_cost,
            )),
            Optimizer::ConjugateGradient => {
                let line_search = MoreThuenteLineSearch::new().with_c(1e-4, 0.1)?;
                let inner = NonlinearConjugateGradient::new(line_search, PolakRibiere::new())
                    .restart_iters(u0.len() as u64)
                    .restart_orthogonality(0.1);
                AnySolver::Cg(Box::new(Converging {
                    inner,
                    tol_grad: settings.gradient_tolerance,
                    tol_cost,
                }))
            }
        };
        Ok(Self {
            solver,
            state: HyperState::new().param(u0),
        })
    }

    /// Runs until `max_iters` iterations in all; `progress` (with the
    /// start's number and the objective's scale) hears of every iteration.
    /// Returns the iterations so far, and the stepper itself when it
    /// stopped at the limit (it can go on), `None` when it stopped for
    /// another reason (converged, or no step lowers the objective).
    ///
    /// # Errors
    /// The solver's or the objective's error (the stepper is lost; the best
    /// point seen is still recorded by `problem`).
    pub(super) fn advance(
        self,
        problem: &Negated<'_>,
        max_iters: u64,
        progress: Option<(&Arc<dyn FitProgress>, usize, f64)>,
    ) -> Result<(u64, Option<Self>), ArgminError> {
        let reporter = progress.map(|(p, start, scale)| Reporter {
            progress: Arc::clone(p),
            start,
            scale,
        });
        let Self { solver, state } = self;
        let (solver, state) = match solver {
            AnySolver::Lbfgs(s) => {
                let (s, state) = execute(problem, s, state, max_iters, reporter)?;
                (AnySolver::Lbfgs(s), state)
            }
            AnySolver::Cg(s) => {
                let (s, state) = execute(problem, *s, state, max_iters, reporter)?;
                (AnySolver::Cg(Box::new(s)), state)
            }
        };
        let iterations = state.get_iter();
        let reason = state.get_termination_reason();
        tracing::debug!(iterations, ?reason, "optimiser start paused or finished");
        let paused = matches!(reason, Some(TerminationReason::MaxItersReached));
        Ok((iterations, paused.then_some(Self { solver, state })))
    }
}

/// Runs `solver` from `state` (fresh, or paused at an earlier limit) up to
/// `max_iters` iterations in all.
fn execute<'a, 'b, S>(
    problem: &'a Negated<'b>,
    solver: S,
    mut state: HyperState,
    max_iters: u64,
    reporter: Option<Reporter>,
) -> Result<(S, HyperState), ArgminError>
where
    S: Solver<&'a Negated<'b>, HyperState>,
{
    // A paused state carries its "limit reached" status; the executor
    // skips the solver's `init` when the state has iterations already.
    state.termination_status = TerminationStatus::NotTerminated;
    let state = state.max_iters(max_iters);
    let mut executor = Executor::new(problem, solver).configure(|_| state);
    if let Some(r) = reporter {
        executor = executor.add_observer(r, ObserverMode::Always);
    }
    let result = executor.run()?;
    Ok((result.solver, result.state))
}
