//! One local model `m`: its centre `c_m`, lengthscales `λ_m`, the Gaussian
//! activation `η_m(x) = exp(−½ Σ_d (x_d − c_md)² / λ_md²)`, the localised
//! linear features `φ_m(x) = η_m(x) · [x − c_m; 1]`, the decayed statistic
//! `S_φφ`, the [`WeightPosterior`], and the gradient step on `log λ_m` of
//! the paper's variational bound.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::blas;
use super::params::IlgrParams;
use super::weights::WeightPosterior;

/// Largest change of one `log λ` in one update: a bad sample cannot move a
/// lengthscale by more than about 10 %.
pub const MAX_LOG_LENGTHSCALE_STEP: f64 = 0.1;

/// What happened to a model in one update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UpdateOutcome {
    /// The posterior was recomputed from the sufficient statistics.
    pub refreshed: bool,
    /// Every ARD precision now exceeds the pruning threshold.
    pub prunable: bool,
}

/// A local linear model with a Gaussian localiser.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocalModel {
    /// Centre `c_m` (standardised input units).
    pub centre: Vec<f64>,
    /// Lengthscales `λ_m`, one per input (standardised input units).
    pub lengthscale: Vec<f64>,
    /// Decayed `S_φφ = Σ_n κ^(t−n) φ_n φ_nᵀ` (`K × K`, `K = d + 1`).
    pub s_phi_phi: DMatrix<f64>,
    /// Effective number of updates `Σ_n κ^(t−n)`.
    pub n_eff: f64,
    /// Updates since the last exact refresh of the weight posteriors.
    pub updates_since_refresh: usize,
    /// The posterior over the weights (one mean per output) and precisions.
    pub posterior: WeightPosterior,
    /// `1 / λ_d²`, derived from `lengthscale`.
    #[serde(skip)]
    inv_lengthscale_sq: Vec<f64>,
}

impl LocalModel {
    /// A model centred at `centre` with lengthscale `lengthscale` in every
    /// dimension and the prior over its weights for `n_outputs` outputs.
    pub fn new(centre: &[f64], lengthscale: f64, n_outputs: usize, params: &IlgrParams) -> Self {
        let k = centre.len() + 1;
        let mut model = Self {
            centre: centre.to_vec(),
            lengthscale: vec![lengthscale; centre.len()],
            s_phi_phi: DMatrix::zeros(k, k),
            n_eff: 0.0,
            updates_since_refresh: 0,
            posterior: WeightPosterior::prior(k, n_outputs, &params.weight_precision_prior),
            inv_lengthscale_sq: Vec::new(),
        };
        model.sync_lengthscales();
        model
    }

    /// Recomputes the cached `1 / λ²` (after deserialising).
    pub fn sync_lengthscales(&mut self) {
        self.inv_lengthscale_sq = self.lengthscale.iter().map(|l| 1.0 / (l * l)).collect();
    }

    /// Number of weights `K = d + 1`.
    pub fn n_weights(&self) -> usize {
        self.centre.len() + 1
    }

    /// The squared scaled distance `Σ_d (x_d − c_md)² / λ_md²`, so that
    /// `η_m(x) = exp(−½ ·)`.
    pub fn sq_distance(&self, x: &[f64]) -> f64 {
        let mut acc = [0.0; 4];
        let chunks = x
            .chunks_exact(4)
            .zip(self.centre.chunks_exact(4))
            .zip(self.inv_lengthscale_sq.chunks_exact(4));
        for ((xs, cs), ws) in chunks {
            for l in 0..4 {
                let dx = xs[l] - cs[l];
                acc[l] += dx * dx * ws[l];
            }
        }
        let tail = x.len() - x.len() % 4;
        let rest: f64 = (tail..x.len())
            .map(|i| (x[i] - self.centre[i]).powi(2) * self.inv_lengthscale_sq[i])
            .sum();
        (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
    }

    /// The activation `η_m(x) = exp(−½ Σ_d (x_d − c_md)² / λ_md²)`.
    pub fn activation(&self, x: &[f64]) -> f64 {
        (-0.5 * self.sq_distance(x)).exp()
    }

    /// Writes `φ_m(x) = η · [x − c_m; 1]` into `phi` (length `K`).
    pub fn features(&self, x: &[f64], eta: f64, phi: &mut DVector<f64>) {
        let d = self.centre.len();
        for i in 0..d {
            phi[i] = eta * (x[i] - self.centre[i]);
        }
        phi[d] = eta;
    }

    /// One online update with features `phi` at input `x`, the E-step's
    /// latent means `μ_f` (one per output) and the sample's total noise
    /// variance `s`: decays and extends `S_φφ`, updates the weight posterior
    /// (rank one), the noise and ARD precisions, takes a gradient step on
    /// `log λ`, and every `refresh_every` updates recomputes the posterior
    /// and the noise's squared errors exactly.
    pub fn update(
        &mut self,
        x: &[f64],
        phi: &DVector<f64>,
        latent_means: &[f64],
        total_variance: f64,
        params: &IlgrParams,
        scratch: &mut DVector<f64>,
    ) -> UpdateOutcome {
        let kappa = params.forgetting;
        let n_outputs = latent_means.len() as f64;
        let k = phi.len();
        blas::rank_one_update(self.s_phi_phi.as_mut_slice(), k, 1.0, phi.as_slice(), kappa);
        self.n_eff = kappa * self.n_eff + 1.0;
        self.updates_since_refresh += 1;
        let mut needs_refresh = self.updates_since_refresh >= params.refresh_every;
        let noise_prior = &params.model_noise_precision_prior;
        let post = &mut self.posterior;
        let beta = post.noise.mean_precision(noise_prior);
        match post.observe(phi, latent_means, beta, kappa, scratch) {
            Some(obs) => {
                // Between refreshes each sample's error is taken under the
                // posterior right after it; the refresh re-evaluates them all.
                post.noise.observe(
                    kappa,
                    obs.sq_residual + n_outputs * obs.fitted_variance,
                    total_variance,
                    n_outputs,
                );
                post.update_ard(&params.weight_precision_prior);
                if params.lengthscale_learning_rate > 0.0 && self.n_eff >= params.lengthscale_warmup
                {
                    // Σ_o E[β] (φᵀ E[w_o w_oᵀ] φ − μ_f,o φᵀμ_w,o): the data
                    // term of the gradient of the negative bound with respect
                    // to log λ_d, up to the factor (x_d − c_d)² / λ_d².
                    let beta = post.noise.mean_precision(noise_prior);
                    let scale = beta * (obs.fit_term + n_outputs * obs.fitted_variance);
                    self.lengthscale_step(x, scale, params);
                }
            }
            None => needs_refresh = true,
        }
        let mut outcome = UpdateOutcome::default();
        if needs_refresh {
            self.refresh(params);
            outcome.refreshed = true;
        }
        outcome.prunable = params
            .prune_precision
            .is_some_and(|threshold| self.posterior.ard.iter().all(|&a| a > threshold));
        outcome
    }

    /// Recomputes the weight posterior from the sufficient statistics with
    /// the current precisions, then the noise's squared errors under it and
    /// the ARD precisions.
    pub fn refresh(&mut self, params: &IlgrParams) {
        let post = &mut self.posterior;
        let beta = post
            .noise
            .mean_precision(&params.model_noise_precision_prior);
        if post.refresh(&self.s_phi_phi, beta) {
            post.noise
                .set_sq_error_sum(post.expected_sq_error(&self.s_phi_phi));
            post.update_ard(&params.weight_precision_prior);
        } else {
            tracing::warn!(
                "ILGR local model: weight precision matrix not factorisable; kept the rank-one posterior"
            );
        }
        self.updates_since_refresh = 0;
    }

    /// `log λ_d ← log λ_d − rate · g · (x_d − c_d)² / λ_d²`, the step
    /// clipped to [`MAX_LOG_LENGTHSCALE_STEP`] and `λ` to the bounds.
    fn lengthscale_step(&mut self, x: &[f64], gradient_scale: f64, params: &IlgrParams) {
        if !gradient_scale.is_finite() {
            return;
        }
        let [lo, hi] = params.lengthscale_bounds;
        let rate = params.lengthscale_learning_rate;
        let dims = x.iter().zip(&self.centre).zip(
            self.lengthscale
                .iter_mut()
                .zip(&mut self.inv_lengthscale_sq),
        );
        for ((xi, ci), (l, inv_sq)) in dims {
            let dx = xi - ci;
            let grad = gradient_scale * dx * dx * *inv_sq;
            let step = (rate * grad).clamp(-MAX_LOG_LENGTHSCALE_STEP, MAX_LOG_LENGTHSCALE_STEP);
            *l = (*l * (-step).exp()).clamp(lo, hi);
            *inv_sq = 1.0 / (*l * *l);
        }
    }
}
