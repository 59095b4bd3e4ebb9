//! One optimiser start with argmin: the bounded projected L-BFGS
//! ([`ProjectedLbfgs`], L-BFGS-B's behaviour) or Polak–Ribière nonlinear
//! conjugate gradient (Moré–Thuente line search, bounds as penalties), with
//! the same stopping rules (gradient norm, change of the objective).

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

use super::projected_lbfgs::ProjectedLbfgs;
use super::{CostTolerance, LogBounds, Negated, Optimizer, OptimizerSettings};

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
/// the objective to maximise: `−cost / scale`.
struct Reporter {
    progress: Arc<dyn FitProgress>,
    start: usize,
    scale: f64,
}

impl Observe<HyperState> for Reporter {
    fn observe_iter(&mut self, state: &HyperState, _kv: &KV) -> Result<(), ArgminError> {
        self.progress.iteration(
            self.start,
            state.get_iter(),
            -state.get_best_cost() / self.scale,
        );
        Ok(())
    }
}

/// Runs one start from `u0`; returns the iterations. The best point seen is
/// recorded by `problem` whatever happens; `progress` (with the start's
/// number and the objective's scale) hears of every iteration.
pub(super) fn run(
    problem: &Negated<'_>,
    bounds: &[LogBounds],
    u0: Vec<f64>,
    settings: &OptimizerSettings,
    tol_cost: CostTolerance,
    progress: Option<(&Arc<dyn FitProgress>, usize, f64)>,
) -> Result<u64, ArgminError> {
    let reporter = progress.map(|(p, start, scale)| Reporter {
        progress: Arc::clone(p),
        start,
        scale,
    });
    let converging_cg = |inner| Converging {
        inner,
        tol_grad: settings.gradient_tolerance,
        tol_cost,
    };
    match settings.optimizer {
        Optimizer::Lbfgs => {
            let solver = ProjectedLbfgs::new(
                bounds.iter().map(LogBounds::lower).collect(),
                bounds.iter().map(LogBounds::upper).collect(),
                settings.lbfgs_memory,
                settings.gradient_tolerance,
                tol_cost,
            );
            let mut executor = Executor::new(problem, solver)
                .configure(|s| s.param(u0).max_iters(settings.max_iters));
            if let Some(r) = reporter {
                executor = executor.add_observer(r, ObserverMode::Always);
            }
            executor.run().map(|r| {
                tracing::debug!(
                    iterations = r.state().get_iter(),
                    reason = ?r.state().get_termination_reason(),
                    "optimiser start finished"
                );
                r.state().get_iter()
            })
        }
        Optimizer::ConjugateGradient => {
            let line_search = MoreThuenteLineSearch::new().with_c(1e-4, 0.1)?;
            let solver = NonlinearConjugateGradient::new(line_search, PolakRibiere::new())
                .restart_iters(u0.len() as u64)
                .restart_orthogonality(0.1);
            let mut executor = Executor::new(problem, converging_cg(solver))
                .configure(|s| s.param(u0).max_iters(settings.max_iters));
            if let Some(r) = reporter {
                executor = executor.add_observer(r, ObserverMode::Always);
            }
            executor.run().map(|r| r.state().get_iter())
        }
    }
}
