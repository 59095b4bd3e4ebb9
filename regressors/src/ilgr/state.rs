//! The learned state of an ILGR and its two operations in standardised
//! target units: one online step (model creation, the E-step over the
//! latent `f_m`, the local updates, pruning) and the prediction at one input.
//! Both cost `O(M d + A K²)` for `M` models, `A` of them active, and
//! `K = d + 1` weights, whatever the number of samples seen.

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use super::gamma::GammaStats;
use super::local_model::LocalModel;
use super::params::IlgrParams;

/// Everything needed to continue learning or predicting, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IlgrState {
    /// The settings it was trained with.
    pub params: IlgrParams,
    /// Number of input columns `d`.
    pub n_inputs: usize,
    /// Subtracted from each target before learning (target units).
    pub target_offset: Vec<f64>,
    /// Each target is divided by this after the offset (target units).
    pub target_scale: Vec<f64>,
    /// Statistics of the output noise precision `β_y`.
    pub output_noise: GammaStats,
    /// The local models.
    pub models: Vec<LocalModel>,
    /// Online updates so far (over all passes).
    pub samples_seen: u64,
    /// Local models created so far.
    pub models_created: u64,
    /// Local models pruned so far.
    pub models_pruned: u64,
}

/// Reusable buffers of one online step; not part of the state.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    active: Vec<(usize, f64)>,
    phis: Vec<DVector<f64>>,
    fitted: Vec<f64>,
    sigma: Vec<f64>,
    latent: Vec<f64>,
    scratch: DVector<f64>,
    prune: Vec<usize>,
}

/// Keeps the `max_active` entries of `active` with the smallest squared
/// distance, i.e. the largest activation (ties broken by model index, so the
/// choice is deterministic), in model order.
fn keep_most_active(active: &mut Vec<(usize, f64)>, max_active: usize) {
    if active.len() > max_active {
        let nearest_first =
            |a: &(usize, f64), b: &(usize, f64)| a.1.total_cmp(&b.1).then_with(|| a.0.cmp(&b.0));
        active.select_nth_unstable_by(max_active - 1, nearest_first);
        active.truncate(max_active);
        active.sort_unstable_by_key(|a| a.0);
    }
}

impl IlgrState {
    /// An empty model (no local models yet) for `n_inputs` inputs and the
    /// given target scaling.
    pub fn new(
        params: IlgrParams,
        n_inputs: usize,
        target_offset: Vec<f64>,
        target_scale: Vec<f64>,
    ) -> Self {
        Self {
            params,
            n_inputs,
            output_noise: GammaStats::default(),
            target_offset,
            target_scale,
            models: Vec::new(),
            samples_seen: 0,
            models_created: 0,
            models_pruned: 0,
        }
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.target_scale.len()
    }

    /// `−2 ln(cutoff)`: the squared scaled distance beyond which a model is
    /// inactive.
    fn max_sq_distance(&self) -> f64 {
        let cutoff = self.params.update_cutoff;
        if cutoff > 0.0 {
            -2.0 * cutoff.ln()
        } else {
            f64::INFINITY
        }
    }

    /// The initial lengthscale of a new model, `init_lengthscale · √d`
    /// within the bounds.
    pub fn initial_lengthscale(&self) -> f64 {
        let [lo, hi] = self.params.lengthscale_bounds;
        (self.params.init_lengthscale * (self.n_inputs as f64).sqrt()).clamp(lo, hi)
    }

    /// The models that take part at `x`: activation at least
    /// `update_cutoff`, at most `max_active_models` of them (the most
    /// activated), as `(index, η)` in model order; and the largest
    /// activation over all models. Selecting on squared distances, only the
    /// kept models pay for an `exp`.
    fn active_models(&self, x: &[f64], active: &mut Vec<(usize, f64)>) -> f64 {
        let max_sq = self.max_sq_distance();
        active.clear();
        let mut min_sq = f64::INFINITY;
        for (m, model) in self.models.iter().enumerate() {
            let sq = model.sq_distance(x);
            min_sq = min_sq.min(sq);
            if sq <= max_sq {
                active.push((m, sq));
            }
        }
        keep_most_active(active, self.params.max_active_models);
        for entry in active.iter_mut() {
            entry.1 = (-0.5 * entry.1).exp();
        }
        (-0.5 * min_sq).exp()
    }

    /// One online step with input `x` and standardised targets `t`; both
    /// have been checked for width and finiteness.
    pub fn step(&mut self, x: &[f64], t: &[f64], ws: &mut Workspace) {
        let (o, k) = (self.n_outputs(), self.n_inputs + 1);
        let max_eta = self.active_models(x, &mut ws.active);
        let p = &self.params;
        if max_eta < p.w_gen && self.models.len() < p.max_models {
            let lengthscale = self.initial_lengthscale();
            self.models.push(LocalModel::new(x, lengthscale, o, p));
            // The new model (η = 1) replaces the least active one if full.
            if ws.active.len() >= p.max_active_models {
                let weakest = ws
                    .active
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.1.total_cmp(&b.1.1).then_with(|| b.1.0.cmp(&a.1.0)))
                    .map(|(i, _)| i);
                if let Some(i) = weakest {
                    ws.active.remove(i);
                }
            }
            ws.active.push((self.models.len() - 1, 1.0));
            self.models_created += 1;
        }
        let n_active = ws.active.len();
        while ws.phis.len() < n_active {
            ws.phis.push(DVector::zeros(k));
        }
        if ws.scratch.len() != k {
            ws.scratch = DVector::zeros(k);
        }
        for (phi, &(m, eta)) in ws.phis.iter_mut().zip(&ws.active) {
            self.models[m].features(x, eta, phi);
        }
        let total_variance = self.e_step(t, ws);
        ws.prune.clear();
        for (i, &(m, _)) in ws.active.iter().enumerate() {
            let outcome = self.models[m].update(
                x,
                &ws.phis[i],
                &ws.latent[i * o..(i + 1) * o],
                total_variance,
                &self.params,
                &mut ws.scratch,
            );
            if outcome.prunable {
                ws.prune.push(m);
            }
        }
        if !ws.prune.is_empty() {
            // `active` is in model order, so `prune` is ascending.
            for &m in ws.prune.iter().rev() {
                self.models.remove(m);
            }
            self.models_pruned += ws.prune.len() as u64;
            tracing::debug!(
                pruned = ws.prune.len(),
                remaining = self.models.len(),
                "ILGR local models pruned"
            );
        }
        self.samples_seen += 1;
    }

    /// The E-step: the posterior of the latent `f_m,o` of every active model
    /// given `y_o = Σ_m f_m,o + ε_y,o`, and the update of `q(β_y)`. With
    /// `σ_m = 1/E[β_f,m]`, `s = 1/E[β_y] + Σ_m σ_m` and the residual
    /// `r_o = y_o − Σ_m φ_mᵀμ_w,m,o`: `μ_f,m,o = φ_mᵀμ_w,m,o + σ_m r_o / s`,
    /// with variance `σ_m − σ_m² / s`; the noise `ε_y,o` has posterior mean
    /// `r_o σ_y / s` and variance `σ_y − σ_y² / s` (see [`super::gamma`]).
    /// Writes `μ_f` into the workspace and returns `s`.
    fn e_step(&mut self, t: &[f64], ws: &mut Workspace) -> f64 {
        let p = &self.params;
        let o = self.n_outputs();
        let n_active = ws.active.len();
        ws.sigma.clear();
        for &(m, _) in &ws.active {
            let noise = &self.models[m].posterior.noise;
            ws.sigma
                .push(noise.variance(&p.model_noise_precision_prior));
        }
        let sigma_y = self.output_noise.variance(&p.output_noise_precision_prior);
        let s = sigma_y + ws.sigma.iter().sum::<f64>();
        ws.fitted.resize(n_active, 0.0);
        ws.latent.resize(n_active * o, 0.0);
        let mut noise_sq = 0.0;
        for (out, &target) in t.iter().enumerate() {
            let mut prediction = 0.0;
            for (i, &(m, _)) in ws.active.iter().enumerate() {
                ws.fitted[i] = self.models[m].posterior.predict_mean(&ws.phis[i], out);
                prediction += ws.fitted[i];
            }
            let r = target - prediction;
            for (i, (fitted, sigma)) in ws.fitted.iter().zip(&ws.sigma).enumerate() {
                ws.latent[i * o + out] = fitted + sigma / s * r;
            }
            noise_sq += (r * sigma_y / s).powi(2);
        }
        self.output_noise
            .observe(p.forgetting, noise_sq, s, o as f64);
        s
    }

    /// Predictive mean and variance at `x` in standardised target units:
    /// mean `Σ_m φ_mᵀμ_w,m,o`, variance (the same for every output)
    /// `1/E[β_y] + Σ_m (1/E[β_f,m] + φ_mᵀΣ_w,m φ_m)` over the active models,
    /// plus the unexplored-region term. `phi` holds `K` values and `active`
    /// is a buffer.
    pub fn predict_standardised(
        &self,
        x: &[f64],
        phi: &mut DVector<f64>,
        active: &mut Vec<(usize, f64)>,
        mean: &mut [f64],
    ) -> f64 {
        let p = &self.params;
        let max_eta = self.active_models(x, active);
        let mut variance = self.output_noise.variance(&p.output_noise_precision_prior);
        mean.fill(0.0);
        for &(m, eta) in active.iter() {
            let model = &self.models[m];
            model.features(x, eta, phi);
            let post = &model.posterior;
            for (out, v) in mean.iter_mut().enumerate() {
                *v += post.predict_mean(phi, out);
            }
            variance +=
                post.noise.variance(&p.model_noise_precision_prior) + post.predict_variance(phi);
        }
        let uncovered = (1.0 - max_eta / p.w_gen).max(0.0);
        variance + p.unexplored_variance * uncovered * uncovered
    }
}
