//! Gamma-distributed precisions: the hyperprior `Gamma(a₀, b₀)` and the
//! decayed statistics of a noise precision's variational posterior
//! `q(β) = Gamma(a₀ + ½ N, b₀ + ½ Σ_n (e_n² + σ_n²))`, with `N` and the sums
//! multiplied by the forgetting factor before each new sample.
//!
//! In ILGR the latent variance of a sample, `σ_n² = σ − σ² / s_n` (`σ =
//! 1/E[β]`, `s_n` the sample's total noise variance, see [`super::state`]),
//! depends on the precision being estimated. The batch update re-evaluates
//! it for every sample at each iteration; an online sum would freeze each
//! sample's term at the `σ` of its time and, with `A` models sharing a
//! residual, `σ` would shrink only like `t^(−1/A)`. We re-evaluate the past
//! terms at the current `σ`, keeping `s_n`: `E[β] = 1/σ` with `σ` the
//! positive root of `a₀ σ = b₀ + ½ E − ½ σ² H`, `E = Σ_n e_n²`,
//! `H = Σ_n 1/s_n` — the fixed point of the batch update for this factor.

use serde::{Deserialize, Serialize};

/// A Gamma hyperprior `Gamma(shape, rate)` on a precision; its mean is
/// `shape / rate`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GammaPrior {
    /// Shape `a₀ > 0`.
    pub shape: f64,
    /// Rate `b₀ > 0`.
    pub rate: f64,
}

impl GammaPrior {
    /// A prior with the given shape and rate.
    pub const fn new(shape: f64, rate: f64) -> Self {
        Self { shape, rate }
    }

    /// Prior mean of the precision, `shape / rate`.
    pub fn mean(&self) -> f64 {
        self.shape / self.rate
    }

    /// Both parameters positive and finite, and so is the mean.
    pub fn is_valid(&self) -> bool {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        positive(self.shape) && positive(self.rate) && positive(self.mean())
    }

    /// Posterior mean `E[α] = (a₀ + ½ o) / (b₀ + ½ Σ_o E[w_o²])` of the ARD
    /// precision shared by one weight of `o` outputs whose posterior second
    /// moments sum to `second_moment = Σ_o (μ_o² + σ²)`.
    pub fn ard_posterior_mean(&self, second_moment: f64, n_outputs: f64) -> f64 {
        (self.shape + 0.5 * n_outputs) / (self.rate + 0.5 * second_moment)
    }
}

/// Decayed sufficient statistics of a noise precision's posterior.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct GammaStats {
    /// Effective number of observations `N = Σ_n κ^(t−n)`.
    pub count: f64,
    /// `½ Σ_n κ^(t−n) e_n²`: half the decayed squared posterior-mean errors
    /// plus the weight uncertainty.
    pub half_sum_sq: f64,
    /// `Σ_n κ^(t−n) / s_n`: the decayed inverse total noise variances.
    pub inv_total_sum: f64,
}

impl GammaStats {
    /// Forgets by `kappa`, then adds `n_obs` observations (one per output)
    /// with summed expected squared error `sq_error` (without the latent
    /// variance) and total noise variance `total_variance = s_n`.
    pub fn observe(&mut self, kappa: f64, sq_error: f64, total_variance: f64, n_obs: f64) {
        self.count = kappa * self.count + n_obs;
        self.half_sum_sq = kappa * self.half_sum_sq + 0.5 * sq_error;
        self.inv_total_sum = kappa * self.inv_total_sum + n_obs / total_variance;
    }

    /// Replaces the decayed sum of squared errors by `sum_sq_error`, the
    /// same sum re-evaluated under the current posterior (see
    /// [`super::weights::WeightPosterior::expected_sq_error`]).
    pub fn set_sq_error_sum(&mut self, sum_sq_error: f64) {
        self.half_sum_sq = 0.5 * sum_sq_error;
    }

    /// The noise variance `σ = 1/E[β]` under `prior`: the positive root of
    /// `½ H σ² + a₀ σ − (b₀ + ½ E) = 0`.
    pub fn variance(&self, prior: &GammaPrior) -> f64 {
        let c = prior.rate + self.half_sum_sq;
        let a = prior.shape;
        2.0 * c / (a + (a * a + 2.0 * self.inv_total_sum * c).sqrt())
    }

    /// Posterior mean of the precision, `E[β] = 1/σ`.
    pub fn mean_precision(&self, prior: &GammaPrior) -> f64 {
        1.0 / self.variance(prior)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_data_the_precision_is_the_prior_mean() {
        let prior = GammaPrior::new(2.0, 0.5);
        assert_eq!(GammaStats::default().mean_precision(&prior), 4.0);
    }

    #[test]
    fn the_variance_solves_the_batch_fixed_point() {
        // a σ = b₀ + ½ Σ (e_n² + σ − σ²/s_n) with a = a₀ + ½ N.
        let prior = GammaPrior::new(1e-3, 2e-3);
        let mut stats = GammaStats::default();
        let samples = [(0.1, 0.5), (0.02, 0.3), (0.3, 2.0), (0.05, 0.4)];
        for (e2, s) in samples {
            stats.observe(1.0, e2, s, 1.0);
        }
        let v = stats.variance(&prior);
        let rate = prior.rate
            + 0.5
                * samples
                    .iter()
                    .map(|(e2, s)| e2 + v - v * v / s)
                    .sum::<f64>();
        let shape = prior.shape + 0.5 * samples.len() as f64;
        assert!((shape / rate - 1.0 / v).abs() < 1e-12 / v);
    }

    #[test]
    fn a_sample_that_is_all_this_noise_gives_the_conjugate_update() {
        // s_n = σ means the sample's latent variance is zero: q(β) is the
        // plain conjugate posterior Gamma(a₀ + ½N, b₀ + ½Σe²) only if
        // σ²/s_n = σ, i.e. the root of a₀σ = b₀ + ½E − ½Nσ.
        let prior = GammaPrior::new(2.0, 0.5);
        let errors = [0.1f64, -0.3, 0.2];
        // Iterate s_n = σ to the fixed point.
        let mut v = 1.0;
        for _ in 0..200 {
            let mut stats = GammaStats::default();
            for e in errors {
                stats.observe(1.0, e * e, v, 1.0);
            }
            v = stats.variance(&prior);
        }
        let expected = (0.5 + 0.5 * (0.01 + 0.09 + 0.04)) / (2.0 + 1.5);
        assert!((v - expected).abs() < 1e-12, "{v} vs {expected}");
    }

    #[test]
    fn forgetting_discounts_old_observations_geometrically() {
        let mut s = GammaStats::default();
        for _ in 0..1000 {
            s.observe(0.9, 2.0, 0.5, 1.0);
        }
        assert!((s.count - 10.0).abs() < 1e-9);
        assert!((s.half_sum_sq - 10.0).abs() < 1e-9);
        assert!((s.inv_total_sum - 20.0).abs() < 1e-9);
    }
}
