//! Hyperparameter learning of the exact GP: the log marginal likelihood and
//! its analytic gradient in `log θ` (kernel hyperparameters, then the noise
//! variance), maximised by [`crate::hyperopt::maximize`] within the bounds
//! of [`ExactGpParams::bounds`].

use faer::MatRef;

use super::likelihood::log_marginal_likelihood;
use super::params::ExactGpParams;
use crate::RegressorError;
use crate::hyperopt::{Coordinates, LogBounds, Objective, ProgressSink, maximize};
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
    progress: &ProgressSink,
) -> Result<Optimized, RegressorError> {
    let mut bounds: Vec<LogBounds> = kernel
        .param_kinds()
        .into_iter()
        .map(|k| LogBounds::new(params.bounds.of(k)))
        .collect();
    bounds.push(LogBounds::new(params.bounds.noise_variance));
    let mut start = kernel.log_params();
    start.push(noise_variance.ln());
    let coords = Coordinates {
        perturb: vec![true; start.len()],
        start,
        bounds,
    };
    let objective = Lml {
        template: kernel,
        x,
        y,
    };
    let value_scale = 1.0 / (y.nrows() * y.ncols()).max(1) as f64;
    let out = maximize(
        &objective,
        &coords,
        value_scale,
        &params.settings(),
        progress.0.as_ref(),
    )?;
    let (kernel, noise_variance) = objective.hyperparameters(&out.coords);
    Ok(Optimized {
        kernel,
        noise_variance,
        lml: out.value,
        evaluations: out.evaluations,
        iterations: out.iterations,
        start_lml: out.start_values,
    })
}
