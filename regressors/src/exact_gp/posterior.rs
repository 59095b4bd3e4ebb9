//! The GP posterior at fixed hyperparameters (paper eq. 8–9): the mean
//! `K_*ᵀ K_y⁻¹ Y` of every output column sharing `K_y = K + σ_n² I`, and
//! the variance `k(x_*, x_*) − k_*ᵀ K_y⁻¹ k_*` (latent; `+ σ_n²` for a
//! noisy target). Densely, one Cholesky factor `L` serves both (the
//! variance's quadratic form is `‖L⁻¹ k_*‖²`, exact); after an iterative
//! fit, CG gives `K_y⁻¹ Y` and a Krylov basis the quadratic form from below
//! ([`super::iterative::love`]), so no `n × n` factor is formed or kept.

use faer::{Accum, Mat, MatRef};

use super::cholesky::Cholesky;
use super::iterative::love::KrylovVariance;
use super::iterative::{IterativeSolver, iterative_posterior};
use super::likelihood::lml_from_factor;
use crate::dense::gemm;
use crate::kernels::Kernel;
use crate::{GpProblem, RegressorError};

/// Predictive moments in the (standardised) units the posterior was built in.
#[derive(Debug, Clone)]
pub struct Moments {
    /// `m × p` predictive means.
    pub mean: Mat<f64>,
    /// Latent variance per query point (shared by the outputs).
    pub latent_variance: Vec<f64>,
    /// Noise variance to add for a noisy target.
    pub noise_variance: f64,
}

/// A conditioned GP: training inputs, factor and weights.
#[derive(Debug, Clone)]
pub struct Posterior {
    /// The kernel.
    pub kernel: Kernel,
    /// The noise variance `σ_n²`.
    pub noise_variance: f64,
    /// Training inputs.
    pub x: Mat<f64>,
    /// Training targets.
    pub y: Mat<f64>,
    solve: Solve,
    alpha: Mat<f64>,
    /// Log marginal likelihood of the training targets: exact from a dense
    /// factor, an estimate after iterative solves.
    pub lml: f64,
    /// The standard error of `lml` when it is an iterative estimate.
    pub lml_standard_error: Option<f64>,
}

/// How the variance's quadratic form `k_*ᵀ K_y⁻¹ k_*` is computed.
#[derive(Debug, Clone)]
enum Solve {
    /// The Cholesky factor of `K_y`: exact.
    Dense(Cholesky),
    /// A Krylov basis: from below.
    Krylov(KrylovVariance),
}

impl Posterior {
    /// Conditions the GP on `(x, y)`.
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when `K_y` cannot be factorised.
    pub fn new(
        kernel: Kernel,
        noise_variance: f64,
        x: Mat<f64>,
        y: Mat<f64>,
    ) -> Result<Self, RegressorError> {
        let mut ky = kernel.gram(x.as_ref());
        for i in 0..x.nrows() {
            ky[(i, i)] += noise_variance;
        }
        let chol = Cholesky::factor(ky)?;
        let alpha = chol.solve(y.as_ref());
        let lml = lml_from_factor(&chol, y.as_ref(), alpha.as_ref());
        Ok(Self {
            kernel,
            noise_variance,
            x,
            y,
            solve: Solve::Dense(chol),
            alpha,
            lml,
            lml_standard_error: None,
        })
    }

    /// Conditions the GP on `(x, y)` by `solver`'s iterative solves and a
    /// Krylov basis of `variance_rank` columns
    /// ([`super::iterative::iterative_posterior`]).
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when CG or the basis breaks
    /// down.
    pub fn iterative(
        kernel: Kernel,
        noise_variance: f64,
        x: Mat<f64>,
        y: Mat<f64>,
        solver: &IterativeSolver,
        variance_rank: usize,
    ) -> Result<Self, RegressorError> {
        let problem = GpProblem::new(&kernel, noise_variance, x.as_ref(), y.as_ref());
        let solved = iterative_posterior(problem, solver, variance_rank)?;
        Ok(Self {
            kernel,
            noise_variance,
            x,
            y,
            solve: Solve::Krylov(solved.variance),
            alpha: solved.alpha,
            lml: solved.evaluation.lml,
            lml_standard_error: Some(solved.evaluation.lml_standard_error),
        })
    }

    /// Diagonal jitter the factorisation needed (0 after iterative solves).
    pub fn jitter(&self) -> f64 {
        match &self.solve {
            Solve::Dense(chol) => chol.jitter,
            Solve::Krylov(_) => 0.0,
        }
    }

    /// Mean and variance at the rows of `xs`.
    pub fn predict(&self, xs: MatRef<'_, f64>) -> Moments {
        let k_star = self.kernel.cross(self.x.as_ref(), xs); // n × m
        let mut mean = Mat::zeros(xs.nrows(), self.alpha.ncols());
        gemm(
            mean.as_mut(),
            Accum::Replace,
            k_star.transpose(),
            self.alpha.as_ref(),
            1.0,
        );
        let explained: Vec<f64> = match &self.solve {
            Solve::Dense(chol) => {
                let v = chol.solve_lower(k_star.as_ref());
                (0..xs.nrows())
                    .map(|j| v.col(j).iter().map(|a| a * a).sum())
                    .collect()
            }
            Solve::Krylov(basis) => basis.explained(k_star.as_ref()),
        };
        let prior = self.kernel.diag(xs);
        // Rounding can push a variance at a training point a hair below
        // zero; it is zero.
        let latent_variance = (0..xs.nrows())
            .map(|j| (prior[j] - explained[j]).max(0.0))
            .collect();
        Moments {
            mean,
            latent_variance,
            noise_variance: self.noise_variance,
        }
    }
}
