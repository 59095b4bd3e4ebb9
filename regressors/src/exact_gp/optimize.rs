//! Hyperparameter learning of the exact GP: the log marginal likelihood and
//! its analytic gradient in `log θ` (kernel hyperparameters, then the noise
//! variance), maximised by [`crate::hyperopt::maximize`] within the bounds
//! of [`ExactGpParams::bounds`], from the best of several scored candidate
//! starts ([`crate::hyperopt::starts`]).

use faer::MatRef;
use gpodo_traits::StartRecord;

use super::likelihood::log_marginal_likelihood;
use super::params::ExactGpParams;
use crate::RegressorError;
use crate::hyperopt::{LogBounds, Objective, ProgressSink, starts};
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
    /// Every candidate start: its LML and, when optimised, the LML reached.
    pub starts: Vec<StartRecord>,
}

/// The log marginal likelihood as a function of `(log θ, log σ_n²)`.
struct Lml<'a> {
    template: &'a Kernel,
    x: MatRef<'a, f64>,
    y: MatRef<'a, f64>,
}

impl Lml<'_> {
    fn hyperparameters(&self, log_theta: &[f64]) -> (Kernel, f64) {
        let m = log_theta.len() - 1;
        let mut kernel = self.template.clone();
        kernel.set_log_params(&log_theta[..m]);
        (kernel, log_theta[m].exp())
    }
}

impl Objective for Lml<'_> {
    fn evaluate(&self, log_theta: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        let (kernel, noise) = self.hyperparameters(log_theta);
        let eval = log_marginal_likelihood(&kernel, noise, self.x, self.y, true)?;
        Ok((eval.lml, eval.gradient.unwrap_or_default()))
    }
}

/// Learns the kernel hyperparameters and noise variance of
/// `params.kernel` on `(x, y)` by maximising the log marginal likelihood:
/// the candidate starts of [`starts::kernel_bases`] and their seeded perturbations
/// ([`StartPolicy`](crate::hyperopt::StartPolicy)) are scored by their LML,
/// the named bases and the best `start.optimize_best` race (the better
/// half of them after `start.halve_after` iterations), the leader runs to
/// convergence (plus `restarts` perturbations of it), and the highest
/// optimum wins.
///
/// # Errors
/// [`RegressorError::Optimizer`] or [`RegressorError::NotPositiveDefinite`]
/// when no start produced a finite objective.
pub fn maximize_lml(
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    params: &ExactGpParams,
    progress: &ProgressSink,
) -> Result<Optimized, RegressorError> {
    let template = params.kernel.build(x.ncols(), &params.init);
    let mut bounds: Vec<LogBounds> = template
        .param_kinds()
        .into_iter()
        .map(|k| LogBounds::new(params.bounds.of(k)))
        .collect();
    bounds.push(LogBounds::new(params.bounds.noise_variance));
    let objective = Lml {
        template: &template,
        x,
        y,
    };
    let perturb = vec![true; bounds.len()];
    let candidates = starts::with_perturbations(
        starts::kernel_bases(&params.kernel, &params.init, x, params.noise_variance),
        &bounds,
        &perturb,
        params.start.perturbations,
        params.seed,
    );
    let value_scale = 1.0 / (y.nrows() * y.ncols()).max(1) as f64;
    let result = starts::maximize_best(
        &objective,
        candidates,
        |c| {
            let (kernel, noise) = objective.hyperparameters(c);
            log_marginal_likelihood(&kernel, noise, x, y, false).map(|e| e.lml)
        },
        &bounds,
        &perturb,
        &params
            .start
            .with_default_halve_after(starts::EXACT_GP_HALVE_AFTER),
        value_scale,
        &params.settings(),
        progress,
    );
    // The evaluations' buffers are not needed once the search is over.
    crate::dense::release_spare();
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
