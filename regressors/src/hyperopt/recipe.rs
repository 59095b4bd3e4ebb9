//! The one way both GPs learn their hyperparameters: the model states its
//! objective, the bounds of its coordinates and its named base starts; the
//! recipe adds the seeded perturbations, scores every candidate, races the
//! optimiser from the best and runs the leader (with the restarts) to
//! convergence, as the `hyperopt:` settings say.

use gpodo_traits::StartRecord;

use super::race::{Score, StartRace};
use super::starts::with_perturbations;
use super::{Bounds, HyperoptParams, LogBounds, Maximized, Objective, ProgressSink};
use crate::RegressorError;
use crate::kernels::Kernel;

/// The optimiser's coordinates: a bound for each, and whether the seeded
/// perturbations (of candidates and restarts) move it.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchSpace {
    /// One bound per coordinate.
    pub bounds: Vec<LogBounds>,
    /// Whether the perturbations move each coordinate.
    pub perturb: Vec<bool>,
}

impl SearchSpace {
    /// The log-hyperparameters of `kernel`, then the log noise variance,
    /// each within its kind's `bounds`; the perturbations move them all.
    pub fn kernel(kernel: &Kernel, bounds: &Bounds) -> Self {
        let mut log_bounds: Vec<LogBounds> = kernel
            .param_kinds()
            .into_iter()
            .map(|k| LogBounds::new(bounds.of(k)))
            .collect();
        log_bounds.push(LogBounds::new(bounds.noise_variance));
        let perturb = vec![true; log_bounds.len()];
        Self {
            bounds: log_bounds,
            perturb,
        }
    }

    /// This space with `n` more coordinates that are free (unbounded) and
    /// that no perturbation moves, such as learned inducing inputs.
    pub fn with_free(mut self, n: usize) -> Self {
        let len = self.bounds.len() + n;
        self.bounds.resize(len, LogBounds::unbounded());
        self.perturb.resize(len, false);
        self
    }
}

/// What a model asks the recipe to maximise.
pub struct HyperProblem<'a> {
    /// The objective with its gradient.
    pub objective: &'a dyn Objective,
    /// The objective without its gradient (scores candidate starts).
    pub score: Score<'a>,
    /// The coordinates.
    pub space: SearchSpace,
    /// The named base starts, in the optimiser's coordinates.
    pub bases: Vec<(String, Vec<f64>)>,
    /// Normalises the objective (e.g. `1/(n·p)` for a likelihood of `n·p`
    /// values), so that the tolerances mean the same at any data size.
    pub value_scale: f64,
}

/// Learns `problem`'s coordinates as `hyperopt` says, with perturbations
/// drawn from `seed`: returns the best optimum (evaluations and iterations
/// summed over every run) and every candidate start's record.
///
/// # Errors
/// [`RegressorError::Stopped`] when `progress` asked to stop (nothing is
/// returned half-fitted); [`RegressorError::Optimizer`] or the objective's
/// own error when no start produced a finite objective.
pub fn learn(
    problem: &HyperProblem<'_>,
    hyperopt: &HyperoptParams,
    seed: u64,
    progress: &ProgressSink,
) -> Result<(Maximized, Vec<StartRecord>), RegressorError> {
    let space = &problem.space;
    let candidates = with_perturbations(
        problem.bases.clone(),
        &space.bounds,
        &space.perturb,
        hyperopt.start.perturbations,
        seed,
    );
    let race = StartRace {
        objective: problem.objective,
        score: problem.score,
        bounds: &space.bounds,
        perturb: &space.perturb,
        value_scale: problem.value_scale,
        settings: hyperopt.settings(seed),
        progress,
    };
    race.maximize_best(candidates, &hyperopt.start)
}
