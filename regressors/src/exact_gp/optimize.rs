//! Hyperparameter learning of the exact GP: the log marginal likelihood and
//! its analytic gradient in `log θ` (kernel hyperparameters, then the noise
//! variance), maximised by the GPs' one recipe ([`crate::hyperopt::learn`])
//! within the bounds of its `hyperopt:` settings.

use faer::MatRef;
use gpodo_traits::StartRecord;

use super::iterative::{IterativeSolver, log_marginal_likelihood_iterative};
use super::likelihood::log_marginal_likelihood;
use super::params::{ExactGpParams, Solver};
use crate::hyperopt::starts::{self, EXACT_GP_HALVE_AFTER};
use crate::hyperopt::{HyperProblem, HyperoptParams, Objective, ProgressSink, SearchSpace};
use crate::kernels::Kernel;
use crate::{GpProblem, RegressorError};

/// A learned noise variance (of standardised targets) below which the
/// iterative solver's stochastic estimates spread widely: on the ExoTeR
/// table (noise 0.0216) 16 probes were off by tens of nats, on the
/// simulated full-rate rows (noise 0.9) by under one.
const SMALL_NOISE_VARIANCE: f64 = 0.05;

/// Whether `solver: auto` fits `n` rows densely although they are above
/// its crossover: at a learned noise variance below
/// [`SMALL_NOISE_VARIANCE`], where iterative estimates spread, and while
/// the dense path fits in memory.
fn auto_stays_dense(params: &ExactGpParams, n: usize, noise_variance: f64) -> bool {
    params.solver == Solver::Auto
        && noise_variance < SMALL_NOISE_VARIANCE
        && params.solver.may_be_dense(n)
}

/// Whether the posterior of an exact GP with `params` on `n` rows, at the
/// noise variance `noise_variance` it learned, is conditioned by iterative
/// solves rather than a dense factor: as its hyperparameters were learned
/// (`solver: iterative`; `auto` above its crossover unless
/// [`auto_stays_dense`]; here the learned noise decides, where the fit
/// used its subset's).
pub(crate) fn conditions_iteratively(
    params: &ExactGpParams,
    n: usize,
    noise_variance: f64,
) -> bool {
    params.solver.resolve(n) == Solver::Iterative && !auto_stays_dense(params, n, noise_variance)
}

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
    /// Every candidate start: its LML and, when optimised, the LML reached.
    pub starts: Vec<StartRecord>,
}

/// The log marginal likelihood as a function of `(log θ, log σ_n²)`,
/// evaluated densely, or by the iterative solver of this fit.
struct Lml<'a> {
    template: &'a Kernel,
    x: MatRef<'a, f64>,
    y: MatRef<'a, f64>,
    iterative: Option<IterativeSolver>,
    /// Asked between the iterative solver's CG iterations.
    progress: &'a ProgressSink,
}

impl Lml<'_> {
    fn hyperparameters(&self, log_theta: &[f64]) -> (Kernel, f64) {
        let m = log_theta.len() - 1;
        let mut kernel = self.template.clone();
        kernel.set_log_params(&log_theta[..m]);
        (kernel, log_theta[m].exp())
    }
}

impl Lml<'_> {
    /// The likelihood at `log_theta`, and its gradient when asked.
    fn at(
        &self,
        log_theta: &[f64],
        with_gradient: bool,
    ) -> Result<(f64, Option<Vec<f64>>), RegressorError> {
        let (kernel, noise) = self.hyperparameters(log_theta);
        let problem = GpProblem::new(&kernel, noise, self.x, self.y);
        match &self.iterative {
            None => log_marginal_likelihood(problem, with_gradient).map(|e| (e.lml, e.gradient)),
            Some(solver) => {
                log_marginal_likelihood_iterative(problem, with_gradient, solver, || {
                    self.progress.stop_requested()
                })
                .map(|e| (e.lml, e.gradient))
            }
        }
    }
}

impl Objective for Lml<'_> {
    fn evaluate(&self, log_theta: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        let (lml, gradient) = self.at(log_theta, true)?;
        Ok((lml, gradient.unwrap_or_default()))
    }
}

/// Learns the kernel hyperparameters and noise variance of
/// `params.kernel` on `(x, y)` by maximising the log marginal likelihood
/// from the candidate starts of [`starts::kernel_bases`], as
/// `params.hyperopt` says (the start race halved after
/// [`EXACT_GP_HALVE_AFTER`] iterations unless it says otherwise). With
/// `warm`, coordinates `(log θ, log σ_n²)` of an earlier optimum (a warm
/// start), the optimiser runs from there alone: no other base and no
/// perturbation.
///
/// # Errors
/// [`RegressorError::Stopped`] when `progress` asked to stop;
/// [`RegressorError::Optimizer`] or [`RegressorError::NotPositiveDefinite`]
/// when no start produced a finite objective.
pub fn maximize_lml(
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    params: &ExactGpParams,
    progress: &ProgressSink,
    warm: Option<&[f64]>,
) -> Result<Optimized, RegressorError> {
    let n = x.nrows();
    let subset = params.iterative.subset_rows;
    let solver = params.solver.resolve(n);
    if solver == Solver::Iterative && warm.is_none() && subset > 0 && subset < n {
        // The start: a dense fit, from the start policy, on rows spread
        // evenly over the training set; the iterative fit goes on from its
        // optimum alone, where the noise is learned and CG is quick.
        let rows: Vec<usize> = (0..subset).map(|i| i * n / subset).collect();
        let xs = faer::Mat::from_fn(subset, x.ncols(), |i, j| x[(rows[i], j)]);
        let ys = faer::Mat::from_fn(subset, y.ncols(), |i, j| y[(rows[i], j)]);
        let dense = ExactGpParams {
            solver: Solver::Dense,
            ..params.clone()
        };
        let first = maximize_lml(xs.as_ref(), ys.as_ref(), &dense, progress, None)?;
        let mut coords = first.kernel.log_params();
        coords.push(first.noise_variance.ln());
        tracing::debug!(
            rows = subset,
            lml = first.lml,
            "iterative exact GP: the subset's dense optimum"
        );
        let small_noise = first.noise_variance < SMALL_NOISE_VARIANCE;
        let dense_instead = auto_stays_dense(params, n, first.noise_variance);
        let full = ExactGpParams {
            solver: if dense_instead {
                Solver::Dense
            } else {
                Solver::Iterative
            },
            ..params.clone()
        };
        if dense_instead {
            tracing::info!(
                noise_variance = first.noise_variance,
                rows = n,
                "solver auto: the noise learned on the {subset}-row subset is small, where iterative estimates spread; fitting densely from the subset's optimum"
            );
        } else if small_noise {
            tracing::warn!(
                noise_variance = first.noise_variance,
                "the noise variance learned on the {subset}-row subset is small: iterative likelihood estimates then spread by nats to tens of nats (bench/README.md, \"By iterative solves\"); `solver: dense`, or more `iterative.probes` and a higher `iterative.preconditioner_rank`, are safer"
            );
        }
        let mut out = maximize_lml(x, y, &full, progress, Some(&coords))?;
        out.evaluations += first.evaluations;
        out.iterations += first.iterations;
        for s in &mut out.starts {
            s.label = format!("{} ({subset}-row subset's dense optimum)", s.label);
        }
        return Ok(out);
    }
    let template = params.kernel_expr().build(x.ncols(), &params.init);
    // An iterative evaluation keeps K, W and the gradient's scratch alive at
    // once; they are held from one evaluation to the next.
    let _spare = (solver == Solver::Iterative)
        .then(|| crate::dense::SpareLimit::at_least(3 * n * n * std::mem::size_of::<f64>()));
    let objective = Lml {
        template: &template,
        x,
        y,
        iterative: (solver == Solver::Iterative)
            .then(|| IterativeSolver::new(x.nrows(), params.iterative)),
        progress,
    };
    let score = |c: &[f64]| objective.at(c, false).map(|e| e.0);
    let problem = HyperProblem {
        objective: &objective,
        score: &score,
        space: SearchSpace::kernel(&template, &params.hyperopt.bounds),
        bases: match warm {
            Some(coords) => vec![("previous optimum".to_string(), coords.to_vec())],
            None => starts::kernel_bases(
                &params.kernel_expr(),
                &params.init,
                x,
                params.noise_variance,
            ),
        },
        value_scale: 1.0 / (y.nrows() * y.ncols()).max(1) as f64,
    };
    let mut start = params
        .hyperopt
        .start
        .with_default_halve_after(EXACT_GP_HALVE_AFTER);
    if warm.is_some() {
        start.perturbations = 0;
    }
    let hyperopt = HyperoptParams {
        start,
        ..params.hyperopt
    };
    let result = crate::hyperopt::learn(&problem, &hyperopt, params.seed, progress);
    // The evaluations' buffers are not needed once the search is over.
    crate::dense::release_spare();
    // A stop asked inside an evaluation fails that evaluation only; the
    // fit stops as a whole.
    if progress.stop_requested() {
        return Err(RegressorError::Stopped);
    }
    let (out, records) = result?;
    let (kernel, noise_variance) = objective.hyperparameters(&out.coords);
    Ok(Optimized {
        kernel,
        noise_variance,
        lml: out.value,
        evaluations: out.evaluations,
        iterations: out.iterations,
        starts: records,
    })
}
