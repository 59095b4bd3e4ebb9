//! The variational posterior of one local model's weights,
//! `q(w_m,o) = N(μ_w,o, Σ_w)` for each output `o`, with
//! `Σ_w = (E[β_f] S_φφ + E[A])⁻¹` and `μ_w,o = E[β_f] Σ_w S_φf,o` (the
//! paper's update of `q(w_m)`, with the decayed sufficient statistics
//! `S_φφ = Σ_n κ^(t−n) φ_n φ_nᵀ` and `S_φf,o = Σ_n κ^(t−n) φ_n μ_f,n,o`),
//! its noise precision `q(β_f,m)` and its ARD precisions `q(α_m)`. The
//! outputs share `Σ_w` because they share the precisions (see the module
//! documentation of [`super`]).
//!
//! Per sample the posterior follows the rank-one (Sherman–Morrison, i.e.
//! recursive least squares with forgetting) form of "the previous posterior
//! is the prior", `Σ⁻¹ ← κ Σ⁻¹ + β φ φᵀ`, in `O(K²)` for `K = d + 1`
//! weights. That form lets the ARD prior decay with the data and keeps the
//! noise precision of past samples, so every `refresh_every` updates
//! [`WeightPosterior::refresh`] recomputes the exact closed form from the
//! sufficient statistics with the current precisions (`O(K³)`, amortised).
//! With `κ = 1` and fixed precisions both forms are exact Bayesian linear
//! regression.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::blas;
use super::gamma::{GammaPrior, GammaStats};

/// What one rank-one update saw, for the noise and lengthscale updates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// `Σ_o (μ_f,o − φᵀ μ_w,o)²` after the update.
    pub sq_residual: f64,
    /// `Σ_o φᵀμ_w,o (φᵀμ_w,o − μ_f,o)` after the update.
    pub fit_term: f64,
    /// `φᵀ Σ_w φ` after the update.
    pub fitted_variance: f64,
}

/// One local model's posterior over its weights and precisions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WeightPosterior {
    /// Posterior means `μ_w,o`, one column per output (`K × o`).
    pub mean: DMatrix<f64>,
    /// Posterior covariance `Σ_w`, shared by the outputs (`K × K`).
    pub cov: DMatrix<f64>,
    /// Decayed `S_φf,o`, one column per output (`K × o`).
    pub s_phi_f: DMatrix<f64>,
    /// Decayed `Σ_o S_ff,o = Σ_o Σ_n κ^(t−n) μ_f,n,o²`.
    pub s_ff: f64,
    /// Statistics of the local noise precision `β_f,m`.
    pub noise: GammaStats,
    /// Posterior means of the ARD precisions `E[α_k]` (`K`).
    pub ard: DVector<f64>,
}

impl WeightPosterior {
    /// The prior: `μ_w = 0`, `Σ_w = E[A]⁻¹` with `E[α_k]` the hyperprior
    /// mean.
    pub fn prior(k: usize, n_outputs: usize, ard_prior: &GammaPrior) -> Self {
        let alpha = ard_prior.mean();
        Self {
            mean: DMatrix::zeros(k, n_outputs),
            cov: DMatrix::from_diagonal_element(k, k, 1.0 / alpha),
            s_phi_f: DMatrix::zeros(k, n_outputs),
            s_ff: 0.0,
            noise: GammaStats::default(),
            ard: DVector::from_element(k, alpha),
        }
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.mean.ncols()
    }

    /// `φᵀ μ_w,o`.
    pub fn predict_mean(&self, phi: &DVector<f64>, output: usize) -> f64 {
        let k = phi.len();
        blas::dot(
            &self.mean.as_slice()[output * k..(output + 1) * k],
            phi.as_slice(),
        )
    }

    /// `φᵀ Σ_w φ`.
    pub fn predict_variance(&self, phi: &DVector<f64>) -> f64 {
        blas::quadratic_form(self.cov.as_slice(), phi.len(), phi.as_slice())
    }

    /// Learns from one pseudo-observation `targets[o] = μ_f,o` of `w_oᵀφ`
    /// per output, with precision `beta`, after forgetting by `kappa`:
    /// `Σ⁻¹ ← κ Σ⁻¹ + β φφᵀ`, `S_φf ← κ S_φf + φ μ_fᵀ`. `scratch` holds `K`
    /// values. Returns `None` (posterior unchanged) when rounding has made
    /// `Σ_w` indefinite; the caller then refreshes.
    pub fn observe(
        &mut self,
        phi: &DVector<f64>,
        targets: &[f64],
        beta: f64,
        kappa: f64,
        scratch: &mut DVector<f64>,
    ) -> Option<Observation> {
        let k = phi.len();
        let (phi, u) = (phi.as_slice(), scratch.as_mut_slice());
        // u = P φ with P = Σ / κ, the covariance after forgetting.
        blas::matvec(self.cov.as_slice(), k, phi, 1.0 / kappa, u);
        let q = blas::dot(phi, u);
        let denom = 1.0 + beta * q;
        if !(q.is_finite() && q >= 0.0 && denom.is_finite()) {
            return None;
        }
        let (mut sq_residual, mut fit_term) = (0.0, 0.0);
        let means = self.mean.as_mut_slice().chunks_exact_mut(k);
        let s_phi_f = self.s_phi_f.as_mut_slice().chunks_exact_mut(k);
        for ((mean, s_phi_f), &target) in means.zip(s_phi_f).zip(targets) {
            let error = target - blas::dot(mean, phi);
            // μ ← μ + Σ_new φ β e with Σ_new φ = u / (1 + β q).
            blas::axpy(beta * error / denom, u, mean);
            for (s, p) in s_phi_f.iter_mut().zip(phi) {
                *s = kappa * *s + target * p;
            }
            let residual = error / denom;
            let fitted = target - residual;
            sq_residual += residual * residual;
            fit_term += fitted * (fitted - target);
        }
        self.s_ff = kappa * self.s_ff + targets.iter().map(|t| t * t).sum::<f64>();
        // Σ_new = P − β u uᵀ / (1 + β q).
        blas::rank_one_update(self.cov.as_mut_slice(), k, -beta / denom, u, 1.0 / kappa);
        Some(Observation {
            sq_residual,
            fit_term,
            fitted_variance: q / denom,
        })
    }

    /// `Σ_o Σ_n κ^(t−n) E[(μ_f,n,o − w_oᵀφ_n)²] = Σ_o (S_ff,o − 2 μ_oᵀS_φf,o
    /// + μ_oᵀS_φφ μ_o) + o · tr(S_φφ Σ_w)`: the decayed expected squared
    /// errors of all past pseudo-observations under the current posterior,
    /// as the batch update of `q(β_f,m)` has them. `O(o K²)`.
    pub fn expected_sq_error(&self, s_phi_phi: &DMatrix<f64>) -> f64 {
        let k = self.ard.len();
        let s = s_phi_phi.as_slice();
        let mut fit = self.s_ff;
        let means = self.mean.as_slice().chunks_exact(k);
        for (mean, s_phi_f) in means.zip(self.s_phi_f.as_slice().chunks_exact(k)) {
            fit += blas::quadratic_form(s, k, mean) - 2.0 * blas::dot(mean, s_phi_f);
        }
        // tr(S Σ) = Σ_ij S_ij Σ_ij for symmetric matrices.
        let trace = blas::dot(s, self.cov.as_slice());
        fit.max(0.0) + self.n_outputs() as f64 * trace.max(0.0)
    }

    /// Updates `E[α_k] = (a₀ + ½ o) / (b₀ + ½ Σ_o (μ_k,o² + Σ_kk))`.
    pub fn update_ard(&mut self, prior: &GammaPrior) {
        let k = self.ard.len();
        let o = self.n_outputs() as f64;
        for (i, alpha) in self.ard.iter_mut().enumerate() {
            let mut second_moment = o * self.cov.as_slice()[i * k + i];
            for mean in self.mean.as_slice().chunks_exact(k) {
                second_moment += mean[i] * mean[i];
            }
            *alpha = prior.ard_posterior_mean(second_moment, o);
        }
    }

    /// Recomputes the exact posterior `Σ_w = (β S_φφ + diag(α))⁻¹`,
    /// `μ_w = β Σ_w S_φf` with the current precisions. Returns false (and
    /// keeps the posterior) if the precision matrix cannot be factorised even
    /// with a diagonal jitter.
    pub fn refresh(&mut self, s_phi_phi: &DMatrix<f64>, beta: f64) -> bool {
        let k = self.ard.len();
        let mut precision = s_phi_phi * beta;
        for i in 0..k {
            precision[(i, i)] += self.ard[i];
        }
        let scale = precision.diagonal().max().max(f64::MIN_POSITIVE);
        let mut jitter = 0.0;
        for _ in 0..4 {
            let mut p = precision.clone();
            for i in 0..k {
                p[(i, i)] += jitter;
            }
            if let Some(cov) = blas::spd_inverse(p.as_slice(), k) {
                self.cov = DMatrix::from_vec(k, k, cov);
                let means = self.mean.as_mut_slice().chunks_exact_mut(k);
                for (mean, s_phi_f) in means.zip(self.s_phi_f.as_slice().chunks_exact(k)) {
                    blas::matvec(self.cov.as_slice(), k, s_phi_f, beta, mean);
                }
                return true;
            }
            jitter = if jitter == 0.0 {
                1e-12 * scale
            } else {
                jitter * 1e3
            };
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bayesian linear regression solved directly:
    /// `(β X̃ᵀX̃ + A) w = β X̃ᵀ y`, one column of `w` per column of `y`.
    fn blr(
        rows: &[Vec<f64>],
        y: &DMatrix<f64>,
        beta: f64,
        alpha: &[f64],
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let k = alpha.len();
        let x = DMatrix::from_fn(rows.len(), k, |i, j| rows[i][j]);
        let mut a = x.transpose() * &x * beta;
        for i in 0..k {
            a[(i, i)] += alpha[i];
        }
        let b = x.transpose() * y * beta;
        let lu = a.clone().lu();
        (lu.solve(&b).unwrap(), a.try_inverse().unwrap())
    }

    /// Features `[sin t, cos 1.3t − 0.2, 1]` and two outputs.
    fn data() -> (Vec<Vec<f64>>, DMatrix<f64>) {
        let rows: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                let t = i as f64 * 0.37;
                vec![t.sin(), (1.3 * t).cos() - 0.2, 1.0]
            })
            .collect();
        let y = DMatrix::from_fn(rows.len(), 2, |i, o| {
            let r = &rows[i];
            let jitter = 0.05 * ((i * 7 % 5) as f64 - 2.0);
            if o == 0 {
                0.7 * r[0] - 1.1 * r[1] + 0.3 + jitter
            } else {
                -0.2 * r[0] + 0.5 - jitter
            }
        });
        (rows, y)
    }

    fn with_ard(alpha: &[f64]) -> WeightPosterior {
        let mut post = WeightPosterior::prior(alpha.len(), 2, &GammaPrior::new(1.0, 1.0));
        post.ard = DVector::from_column_slice(alpha);
        post.cov = DMatrix::from_diagonal(&post.ard.map(|a| 1.0 / a));
        post
    }

    #[test]
    fn rank_one_updates_without_forgetting_are_bayesian_linear_regression() {
        let (rows, y) = data();
        let (beta, alpha) = (25.0, [0.5, 2.0, 0.1]);
        let mut post = with_ard(&alpha);
        let mut scratch = DVector::zeros(3);
        for (i, r) in rows.iter().enumerate() {
            let phi = DVector::from_column_slice(r);
            let t = [y[(i, 0)], y[(i, 1)]];
            post.observe(&phi, &t, beta, 1.0, &mut scratch).unwrap();
        }
        let (mean, cov) = blr(&rows, &y, beta, &alpha);
        assert!(
            (&post.mean - &mean).amax() < 1e-10,
            "{} vs {}",
            post.mean,
            mean
        );
        assert!((&post.cov - &cov).amax() < 1e-10);
    }

    #[test]
    fn refresh_recomputes_the_closed_form_from_the_statistics() {
        let (rows, y) = data();
        let kappa = 0.95;
        let (beta, alpha) = (10.0, [1.0, 3.0, 0.2]);
        let mut post = with_ard(&alpha);
        let mut s = DMatrix::zeros(3, 3);
        let mut scratch = DVector::zeros(3);
        for (i, r) in rows.iter().enumerate() {
            let phi = DVector::from_column_slice(r);
            s = s * kappa + &phi * phi.transpose();
            let t = [y[(i, 0)], y[(i, 1)]];
            post.observe(&phi, &t, beta, kappa, &mut scratch).unwrap();
        }
        assert!(post.refresh(&s, beta));
        // Forgetting weights row n by κ^(N−1−n): a weighted regression.
        let n = rows.len();
        let w: Vec<f64> = (0..n)
            .map(|i| kappa.powi((n - 1 - i) as i32).sqrt())
            .collect();
        let rows_w: Vec<Vec<f64>> = rows
            .iter()
            .zip(&w)
            .map(|(r, wi)| r.iter().map(|v| v * wi).collect())
            .collect();
        let y_w = DMatrix::from_fn(n, 2, |i, o| y[(i, o)] * w[i]);
        let (mean, cov) = blr(&rows_w, &y_w, beta, &alpha);
        assert!((&post.mean - &mean).amax() < 1e-10);
        assert!((&post.cov - &cov).amax() < 1e-10);
    }

    #[test]
    fn the_expected_squared_error_sums_over_the_past_observations() {
        let (rows, y) = data();
        let mut post = with_ard(&[1.0, 1.0, 1.0]);
        let mut s = DMatrix::zeros(3, 3);
        let mut scratch = DVector::zeros(3);
        for (i, r) in rows.iter().enumerate() {
            let phi = DVector::from_column_slice(r);
            s += &phi * phi.transpose();
            post.observe(&phi, &[y[(i, 0)], y[(i, 1)]], 5.0, 1.0, &mut scratch)
                .unwrap();
        }
        let direct: f64 = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let phi = DVector::from_column_slice(r);
                (0..2)
                    .map(|o| (y[(i, o)] - post.predict_mean(&phi, o)).powi(2))
                    .sum::<f64>()
                    + 2.0 * post.predict_variance(&phi)
            })
            .sum();
        assert!((post.expected_sq_error(&s) - direct).abs() < 1e-9 * direct);
    }

    #[test]
    fn the_reported_terms_are_those_after_the_update() {
        let mut post = WeightPosterior::prior(2, 2, &GammaPrior::new(1.0, 1.0));
        let phi = DVector::from_column_slice(&[0.5, 1.0]);
        let mut scratch = DVector::zeros(2);
        let targets = [2.0, -1.0];
        let obs = post
            .observe(&phi, &targets, 4.0, 1.0, &mut scratch)
            .unwrap();
        let fitted = [post.predict_mean(&phi, 0), post.predict_mean(&phi, 1)];
        let sq: f64 = (0..2).map(|o| (targets[o] - fitted[o]).powi(2)).sum();
        let fit: f64 = (0..2).map(|o| fitted[o] * (fitted[o] - targets[o])).sum();
        assert!((obs.sq_residual - sq).abs() < 1e-14);
        assert!((obs.fit_term - fit).abs() < 1e-14);
        assert!((obs.fitted_variance - post.predict_variance(&phi)).abs() < 1e-14);
    }
}
