//! One optimiser start as a value: its start is evaluated (which fixes the
//! objective's scale), then it is advanced to an iteration limit, possibly
//! in several legs (the start race advances many runs a few iterations
//! each and only the better ones further), and finally turned into a
//! [`Maximized`].

use std::sync::Arc;

use gpodo_traits::FitProgress;

use super::negated::Negated;
use super::solver::Stepper;
use super::{CostTolerance, LogBounds, Maximized, Objective, OptimizerSettings, optimizer_error};
use crate::RegressorError;

/// One optimiser start, advanced leg by leg.
pub(super) struct Run<'a> {
    problem: Negated<'a>,
    /// The solver, while it can go on.
    stepper: Option<Stepper>,
    /// Iterations of the legs that ended without an error.
    iterations: u64,
}

impl<'a> Run<'a> {
    /// Evaluates `objective` at `u` (optimiser coordinates on `bounds`) and
    /// prepares the solver. The objective is scaled by `value_scale`,
    /// further divided by the gradient norm at the start when that exceeds
    /// 1 (see [`Negated`]).
    ///
    /// # Errors
    /// The objective's error at the start (a failed evaluation is not
    /// counted), or the solver's when it cannot be set up.
    pub(super) fn start(
        objective: &'a dyn Objective,
        bounds: &'a [LogBounds],
        u: Vec<f64>,
        value_scale: f64,
        settings: &OptimizerSettings,
    ) -> Result<Self, RegressorError> {
        let problem = Negated::start(objective, bounds, &u, value_scale)?;
        let tol_cost = CostTolerance {
            relative: settings.relative_cost_tolerance,
            unit: problem.scale(),
        };
        let stepper = Stepper::new(bounds, u, settings, tol_cost)
            .map_err(|e| optimizer_error(settings, e))?;
        Ok(Self {
            problem,
            stepper: Some(stepper),
            iterations: 0,
        })
    }

    /// Runs the optimiser on until `max_iters` iterations in all (at least
    /// 1: a run paused at 0 would be set up again), unless it has stopped
    /// already; `progress` (with the start's number) hears of every
    /// iteration. A leg that fails ends the run, keeping the best point
    /// evaluated; its iterations are not counted (the earlier legs' are).
    pub(super) fn advance(
        &mut self,
        max_iters: u64,
        progress: Option<(&Arc<dyn FitProgress>, usize)>,
    ) {
        debug_assert!(max_iters > 0, "a run paused at iteration 0 cannot resume");
        let Some(stepper) = self.stepper.take() else {
            return;
        };
        let scale = self.problem.scale();
        let progress = progress.map(|(p, start)| (p, start, scale));
        match stepper.advance(&self.problem, max_iters, progress) {
            Ok((iterations, stepper)) => {
                self.iterations = iterations;
                self.stepper = stepper;
            }
            Err(e) => {
                tracing::debug!(error = %e, "optimiser stopped early; keeping the best point");
            }
        }
    }

    /// Whether the optimiser stopped only at its iteration limit (so a
    /// higher one would take it further).
    pub(super) fn can_go_on(&self) -> bool {
        self.stepper.is_some()
    }

    /// The best objective so far (unscaled, to maximise).
    pub(super) fn best_value(&self) -> f64 {
        self.problem.best_value()
    }

    /// The best point evaluated and its value (unscaled, to maximise),
    /// with the run's evaluations and iterations.
    pub(super) fn finish(self) -> Maximized {
        let (evaluations, iterations) = (self.problem.evaluations(), self.iterations);
        let (coords, value) = self.problem.into_best();
        Maximized {
            coords,
            value,
            evaluations,
            iterations,
            start_values: vec![value],
        }
    }
}

#[cfg(test)]
mod tests {
    use std::cell::RefCell;

    use super::*;
    use crate::hyperopt::Optimizer;

    /// The Rosenbrock function in `d` coordinates, negated (to maximise),
    /// remembering every point it is evaluated at: curved enough that the
    /// L-BFGS memory and CG's direction matter to every iterate.
    struct Rosenbrock(RefCell<Vec<Vec<f64>>>);

    impl Objective for Rosenbrock {
        fn evaluate(&self, c: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
            self.0.borrow_mut().push(c.to_vec());
            let mut value = 0.0;
            let mut grad = vec![0.0; c.len()];
            for i in 0..c.len() - 1 {
                let (a, b) = (1.0 - c[i], c[i + 1] - c[i] * c[i]);
                value -= a * a + 100.0 * b * b;
                grad[i] += 2.0 * a + 400.0 * b * c[i];
                grad[i + 1] -= 200.0 * b;
            }
            Ok((value, grad))
        }
    }

    fn settings(optimizer: Optimizer) -> OptimizerSettings {
        OptimizerSettings {
            max_iters: 40,
            restarts: 0,
            gradient_tolerance: 1e-12,
            lbfgs_memory: 5,
            ..crate::hyperopt::tests::settings(optimizer)
        }
    }

    /// The points evaluated, the result and the iterations of a run
    /// advanced through the iteration limits `legs`.
    fn run_in_legs(optimizer: Optimizer, legs: &[u64]) -> (Vec<Vec<f64>>, Maximized, u64) {
        let objective = Rosenbrock(RefCell::new(Vec::new()));
        let bounds = vec![LogBounds::new([(-3.0f64).exp(), 3.0f64.exp()]); 6];
        let settings = settings(optimizer);
        let u: Vec<f64> = [-1.2, 1.0, -0.5, 0.8, 1.5, -1.0]
            .iter()
            .zip(&bounds)
            .map(|(c, b)| b.from_log(*c))
            .collect();
        let mut run = Run::start(&objective, &bounds, u, 1.0, &settings).unwrap();
        for &limit in legs {
            run.advance(limit, None);
        }
        let out = run.finish();
        let iterations = out.iterations;
        (objective.0.into_inner(), out, iterations)
    }

    #[test]
    fn a_run_paused_and_resumed_is_the_run_advanced_at_once() {
        for optimizer in [Optimizer::Lbfgs, Optimizer::ConjugateGradient] {
            let (points, out, iterations) = run_in_legs(optimizer, &[40]);
            assert_eq!(iterations, 40, "{optimizer:?} should run to its limit");
            let (points_in_legs, out_in_legs, iterations_in_legs) =
                run_in_legs(optimizer, &[5, 5, 17, 40]);
            // The same points in the same order: the solver keeps its
            // memory (L-BFGS pairs, CG direction) and its iteration count
            // across a pause (a fresh solver from the pause point would
            // step differently).
            assert_eq!(points_in_legs, points, "{optimizer:?}");
            assert_eq!(out_in_legs, out, "{optimizer:?}");
            assert_eq!(iterations_in_legs, 40);
            // A shorter run stops earlier.
            let (short, _, short_iterations) = run_in_legs(optimizer, &[17]);
            assert_eq!(short_iterations, 17);
            assert!(short.len() < points.len() && points.starts_with(&short));
        }
    }

    #[test]
    fn a_run_that_converges_stops_whatever_its_legs() {
        for optimizer in [Optimizer::Lbfgs, Optimizer::ConjugateGradient] {
            let (points, out, iterations) = run_in_legs(optimizer, &[5000]);
            assert!(
                iterations < 5000,
                "{optimizer:?} should converge on its gradient"
            );
            // Paused just before it converges, resumed past it, and resumed
            // again after it stopped (that leg does nothing).
            let legs = [iterations - 1, 5000, 6000];
            let (points_in_legs, out_in_legs, iterations_in_legs) = run_in_legs(optimizer, &legs);
            assert_eq!(points_in_legs, points, "{optimizer:?}");
            assert_eq!(out_in_legs, out, "{optimizer:?}");
            assert_eq!(iterations_in_legs, iterations);
        }
    }
}
