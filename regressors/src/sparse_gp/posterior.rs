//! The sparse GP posterior at fixed hyperparameters, reduced to what
//! on-board prediction needs: the inducing inputs `Z`, the weights
//! `β = Σ⁻¹ K_uf Λ⁻¹ Y` (`m × p`) and `P = K_uu⁻¹ − Σ⁻¹` (`m × m`), so that
//! a query costs `O(m d)` for `k_*`, `O(m)` per output for the mean
//! `k_*ᵀβ` and `O(m²)` for the latent variance `k_** − k_*ᵀ P k_*`.

use faer::{Accum, Mat, MatRef};

use super::bound::factorize;
use crate::dense::gemm;
use crate::exact_gp::posterior::Moments;
use crate::kernels::Kernel;
use crate::scaling::{GpPredictions, scale_queries, unscale_predictions};
use crate::{RegressorError, SparseProblem};
use gpodo_traits::{Error, SampleMatrix, Standardizer};

/// A conditioned sparse GP.
#[derive(Debug, Clone, PartialEq)]
pub struct SparsePosterior {
    /// The kernel.
    pub kernel: Kernel,
    /// The noise variance `σ²`.
    pub noise_variance: f64,
    /// Inducing inputs `Z` (`m × d`).
    pub inducing: Mat<f64>,
    /// `β` (`m × p`).
    pub weights: Mat<f64>,
    /// `P = K_uu⁻¹ − Σ⁻¹` (`m × m`).
    pub variance_matrix: Mat<f64>,
    /// The objective (VFE bound or FITC likelihood) at the training data.
    pub objective: f64,
    /// Diagonal jitter `K_uu` needed beyond the configured one.
    pub extra_jitter: f64,
}

impl SparsePosterior {
    /// Conditions the sparse GP of `problem` on its data; the posterior
    /// keeps copies of the kernel and the inducing inputs.
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when `K_uu` cannot be factorised.
    pub fn new(problem: SparseProblem<'_>) -> Result<Self, RegressorError> {
        let f = factorize(&problem)?;
        let m = problem.n_inducing();
        let gamma = f.lb.solve_upper(f.c.as_ref());
        let weights = f.l.solve_upper(gamma.as_ref());
        // P = L⁻ᵀ (I − B⁻¹) L⁻¹.
        let b_inv = f.lb.inverse();
        let inner = Mat::from_fn(m, m, |a, b| {
            (if a == b { 1.0 } else { 0.0 }) - b_inv[(a, b)]
        });
        let t = f.l.solve_upper(inner.as_ref());
        let pt = f.l.solve_upper(t.transpose());
        let variance_matrix = Mat::from_fn(m, m, |a, b| 0.5 * (pt[(a, b)] + pt[(b, a)]));
        Ok(Self {
            kernel: problem.gp.kernel.clone(),
            noise_variance: problem.gp.noise_variance,
            inducing: problem.z.to_owned(),
            weights,
            variance_matrix,
            objective: f.value,
            extra_jitter: f.l.jitter,
        })
    }

    /// Mean and variance at the rows of `xs`.
    pub fn predict(&self, xs: MatRef<'_, f64>) -> Moments {
        let k_star = self.kernel.cross(xs, self.inducing.as_ref()); // q × m
        let mut mean = Mat::zeros(xs.nrows(), self.weights.ncols());
        gemm(
            mean.as_mut(),
            Accum::Replace,
            k_star.as_ref(),
            self.weights.as_ref(),
            1.0,
        );
        // `P k_*ᵀ` (`m × q`, `P` symmetric): with the queries as columns a
        // one-row query is a matrix-vector product, not a GEMM that packs
        // `P` for a single row.
        let mut pk = Mat::<f64>::zeros(self.inducing.nrows(), xs.nrows());
        gemm(
            pk.as_mut(),
            Accum::Replace,
            self.variance_matrix.as_ref(),
            k_star.as_ref().transpose(),
            1.0,
        );
        let prior = self.kernel.diag(xs);
        let latent_variance = (0..xs.nrows())
            .map(|i| {
                let explained: f64 = (0..k_star.ncols())
                    .map(|j| pk[(j, i)] * k_star[(i, j)])
                    .sum();
                (prior[i] - explained).max(0.0)
            })
            .collect();
        Moments {
            mean,
            latent_variance,
            noise_variance: self.noise_variance,
        }
    }

    /// Mean, latent and noisy variance at raw `inputs` (`d` columns), in
    /// target units: z-scored by `input_scaler`, predicted, and scaled back
    /// by `output_scaler`; `model` names the regressor in errors.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a wrong input width;
    /// [`Error::InvalidInput`] for non-finite inputs.
    pub fn predict_scaled(
        &self,
        model: &str,
        inputs: &SampleMatrix,
        d: usize,
        input_scaler: Option<&Standardizer>,
        output_scaler: Option<&Standardizer>,
    ) -> Result<GpPredictions, Error> {
        let xs = scale_queries(model, inputs, d, input_scaler)?;
        let moments = self.predict(xs.as_ref());
        let (q, p) = (xs.nrows(), moments.mean.ncols());
        let latent = Mat::from_fn(q, p, |i, _| moments.latent_variance[i]);
        let noisy = Mat::from_fn(q, p, |i, _| {
            moments.latent_variance[i] + moments.noise_variance
        });
        unscale_predictions(
            moments.mean.as_ref(),
            latent.as_ref(),
            noisy.as_ref(),
            output_scaler,
        )
    }
}
