//! The log marginal likelihood of an exact GP (paper eq. 7–9, Rasmussen &
//! Williams eq. 2.30 and 5.9) for `p` output columns that share the kernel
//! and the noise (as GPy's `GPRegression` on an `n × p` target):
//!
//! `log p(Y) = −½ Σ_c y_cᵀ K_y⁻¹ y_c − (p/2) log|K_y| − (np/2) log 2π`,
//! `K_y = K + σ_n² I`, and its gradient with respect to the logarithm of
//! every hyperparameter,
//!
//! `∂ log p / ∂θ = ½ Σ_ij W_ij ∂K_y,ij/∂θ`, `W = A Aᵀ − p K_y⁻¹`, `A = K_y⁻¹ Y`.
//!
//! One factorisation serves all outputs; the gradient costs one inverse
//! (`n³`, faer) and a few `O(n²d)` products, with no per-hyperparameter
//! `n × n` temporaries (see the kernels' `accumulate_gradient`).

use faer::{Mat, MatRef};

use super::cholesky::Cholesky;
use crate::dense::{column, for_column_blocks, recycle, trace};
use crate::{GpProblem, RegressorError};

/// `log 2π`.
pub(crate) const LN_2PI: f64 = 1.837_877_066_409_345_3;

/// One evaluation of the objective.
#[derive(Debug, Clone, PartialEq)]
pub struct LmlEvaluation {
    /// `log p(Y | X, θ)`, summed over the outputs.
    pub lml: f64,
    /// `∂ log p/∂ log θ`: the kernel's hyperparameters in
    /// [`crate::kernels::Kernel::log_params`] order, then the noise variance.
    pub gradient: Option<Vec<f64>>,
    /// Diagonal jitter the factorisation needed.
    pub jitter: f64,
}

/// `log p(Y)` from the factor of `K_y` and `A = K_y⁻¹ Y`.
pub fn lml_from_factor(chol: &Cholesky, y: MatRef<'_, f64>, alpha: MatRef<'_, f64>) -> f64 {
    let (n, p) = (y.nrows(), y.ncols());
    let data_fit: f64 = (0..p)
        .map(|c| (0..n).map(|i| y[(i, c)] * alpha[(i, c)]).sum::<f64>())
        .sum();
    -0.5 * data_fit - 0.5 * p as f64 * chol.log_det() - 0.5 * (n * p) as f64 * LN_2PI
}

/// `W = A Aᵀ − p K_y⁻¹` on and below the diagonal (all the kernels'
/// gradients read of the symmetric `W`), written over the lower triangle of
/// `K_y⁻¹` it is given, with `A = K_y⁻¹ Y` (`n × p`), in one pass over
/// column blocks (in parallel, see [`for_column_blocks`]).
fn weights_lower(mut inverse_lower: Mat<f64>, alpha: MatRef<'_, f64>) -> Mat<f64> {
    let (n, p) = (alpha.nrows(), alpha.ncols());
    let scale = -(p as f64);
    let alpha_cols: Vec<std::borrow::Cow<'_, [f64]>> = (0..p).map(|c| column(alpha, c)).collect();
    let mut unused = vec![(); n];
    for_column_blocks(&mut inverse_lower, &mut unused, |j0, columns, _| {
        for (jj, col) in columns.iter_mut().enumerate() {
            let j = j0 + jj;
            for (i, entry) in col.iter_mut().enumerate().skip(j) {
                let outer: f64 = alpha_cols.iter().map(|a| a[i] * a[j]).sum();
                *entry = outer + scale * *entry;
            }
        }
    });
    inverse_lower
}

/// Evaluates the log marginal likelihood of `problem`, and its gradient
/// when asked.
///
/// # Errors
/// [`RegressorError::NotPositiveDefinite`] when `K_y` cannot be factorised.
pub fn log_marginal_likelihood(
    problem: GpProblem<'_>,
    with_gradient: bool,
) -> Result<LmlEvaluation, RegressorError> {
    let GpProblem {
        kernel,
        noise_variance,
        x,
        y,
    } = problem;
    let n = y.nrows();
    // Only lower triangles are formed and read from here on.
    let cache = kernel.gram_lower_with_cache(x);
    let chol = Cholesky::factor_shifted(&cache.k, noise_variance)?;
    let alpha = chol.solve(y);
    let lml = lml_from_factor(&chol, y, alpha.as_ref());
    if !lml.is_finite() {
        return Err(RegressorError::NotPositiveDefinite {
            n,
            jitter_tried: chol.jitter,
        });
    }
    let gradient = with_gradient.then(|| {
        let w = weights_lower(chol.inverse_lower(), alpha.as_ref());
        let mut g = vec![0.0; kernel.n_params() + 1];
        let m = kernel.n_params();
        kernel.accumulate_gradient(x, &cache, w.as_ref(), &mut g[..m]);
        g[m] = noise_variance * trace(w.as_ref());
        recycle(w);
        for v in &mut g {
            *v *= 0.5;
        }
        g
    });
    // The next evaluation reuses these buffers.
    cache.recycle();
    recycle(chol.l);
    Ok(LmlEvaluation {
        lml,
        gradient,
        jitter: chol.jitter,
    })
}
