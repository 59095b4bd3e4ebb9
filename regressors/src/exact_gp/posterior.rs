//! The GP posterior at fixed hyperparameters (paper eq. 8–9): one Cholesky
//! factor of `K_y = K + σ_n² I` serves the mean `K_*ᵀ K_y⁻¹ Y` of every
//! output column sharing it and the variance
//! `k(x_*, x_*) − ‖L⁻¹ k_*‖²` (latent; `+ σ_n²` for a noisy target).

use faer::{Accum, Mat, MatRef};

use super::cholesky::Cholesky;
use super::likelihood::lml_from_factor;
use crate::RegressorError;
use crate::dense::gemm;
use crate::kernels::Kernel;

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
    chol: Cholesky,
    alpha: Mat<f64>,
    /// Log marginal likelihood of the training targets.
    pub lml: f64,
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
            chol,
            alpha,
            lml,
        })
    }

    /// Diagonal jitter the factorisation needed.
    pub fn jitter(&self) -> f64 {
        self.chol.jitter
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
        let v = self.chol.solve_lower(k_star.as_ref());
        let prior = self.kernel.diag(xs);
        let latent_variance = (0..xs.nrows())
            .map(|j| {
                let explained: f64 = v.col(j).iter().map(|a| a * a).sum();
                // Rounding can push a variance at a training point a hair
                // below zero; it is zero.
                (prior[j] - explained).max(0.0)
            })
            .collect();
        Moments {
            mean,
            latent_variance,
            noise_variance: self.noise_variance,
        }
    }
}
