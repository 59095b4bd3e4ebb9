//! Incremental local Gaussian regression (ILGR; Meier, Hennig & Schaal,
//! "Incremental Local Gaussian Regression", NIPS 2014), the online learner
//! of the residual (paper §VI).
//!
//! # Model
//! `y = Σ_m f_m(x) + ε_y`, `f_m(x) = w_mᵀ φ_m(x) + ε_f,m`, with localised
//! linear features `φ_m(x) = η_m(x) · [x − c_m; 1]` and Gaussian activations
//! `η_m(x) = exp(−½ Σ_d (x_d − c_md)² / λ_md²)`; `w_m ~ N(0, A_m⁻¹)` with ARD
//! precisions `α_mk ~ Gamma`, noise precisions `β_y, β_f,m ~ Gamma`. The
//! posterior is factorised, `q(f) Π_m q(w_m) q(β_f,m) q(α_m) · q(β_y)`, and
//! updated one sample at a time, the previous posterior acting as the prior:
//!
//! * **E-step** ([`state::IlgrState::step`]): `q(f_m)` of each active model
//!   from the residual `r = y − Σ_m φ_mᵀ μ_w,m`, shared in proportion to the
//!   models' noise variances: `μ_f,m = φ_mᵀμ_w,m + (σ_m / s) r`,
//!   `σ_f,m² = σ_m − σ_m² / s`, `s = 1/E[β_y] + Σ_m σ_m`, `σ_m = 1/E[β_f,m]`;
//! * **`q(w_m)`** ([`weights`]): `Σ_w = (E[β_f] S_φφ + E[A])⁻¹`,
//!   `μ_w = E[β_f] Σ_w S_φf` with sufficient statistics decayed by the
//!   forgetting factor κ, tracked by rank-one updates and recomputed exactly
//!   every `refresh_every` updates of the model;
//! * **`q(β_f,m)`, `q(β_y)`** ([`gamma`]): `Gamma(a₀ + ½N, b₀ + ½ Σ_n
//!   E[e_n²])` with decayed counts and sums;
//! * **`q(α_mk)`**: `Gamma(a₀ + ½, b₀ + ½(μ_k² + Σ_kk))` (per output; see
//!   below for several outputs);
//! * **lengthscales** ([`local_model`]): a gradient step on `log λ_md` of the
//!   model's expected log likelihood, `∂/∂log λ_d = β Σ_n (x_d − c_d)²/λ_d²
//!   (φᵀ E[wwᵀ] φ − μ_f φᵀμ_w)`, one sample at a time;
//! * **creation**: a sample creates a model centred on itself when no
//!   model's activation reaches `w_gen` (up to `max_models`);
//! * **pruning**: a model whose ARD precisions all exceed `prune_precision`
//!   explains nothing and is removed.
//!
//! The predictive distribution at `x` is `N(Σ_m φ_mᵀμ_w,m, 1/E[β_y] + Σ_m
//! (1/E[β_f,m] + φ_mᵀΣ_w,m φ_m))` (the paper's), plus the unexplored-region
//! term below.
//!
//! # Choices beyond the paper
//! * **Cost independent of the data seen.** Only the models with activation
//!   at least `update_cutoff`, and of those at most `max_active_models` (the
//!   most activated), take part in a sample's E-step (the sum `s` runs over
//!   them), update and prediction, so a step costs `O(M d + A K²)` for `M`
//!   models, `A ≤ max_active_models` active, `K = d + 1`. Forgetting applies
//!   to a model when it is updated, so a model keeps what it learned while
//!   the rover is elsewhere.
//! * **Several outputs** (the residual's vx, vy, vz) share the local models
//!   — centres, lengthscales, activations, `S_φφ`, creation and pruning —
//!   and their precisions `β_f,m`, `α_m`, `β_y` in standardised target
//!   units, as the exact GP's default `outputs: shared` shares one kernel
//!   and one noise; each output has its own weight mean `μ_w,m,o`. So `Σ_w`
//!   is shared and a step costs one rank-one covariance update per model,
//!   not one per output. With one output this is the paper's ILGR.
//! * **Online noise updates.** A batch iteration re-evaluates every past
//!   sample's expected squared error under the current posterior; an online
//!   sum would freeze them at the posterior of their time, and the early,
//!   badly fitted samples then dominate the noise for about `1/(1 − κ)`
//!   updates. At each refresh the local models' errors are re-evaluated from
//!   the sufficient statistics (`S_ff − 2μᵀS_φf + μᵀS_φφμ + tr(S_φφΣ_w)`,
//!   which needs the decayed `S_ff = Σ μ_f²`); in between each sample's error
//!   is taken under the posterior right after it. The latent variance
//!   `σ_m − σ_m²/s_n` of past samples is re-evaluated at the current `σ_m`
//!   in closed form (see [`gamma`]); frozen, it makes `σ_m` shrink only like
//!   `t^(−1/A)` when `A` models share the residuals.
//! * **Predictive variance.** The paper's variance goes to the noise level
//!   far from every model (a finite localised basis is certain where it has
//!   no support). We add `unexplored_variance · (1 − max_m η_m / w_gen)₊²`:
//!   zero wherever a model's activation reaches `w_gen` (where no new model
//!   would be created) and the prior variance of the targets far from all
//!   models. `unexplored_variance: 0` recovers the paper's variance. Where
//!   several models overlap, the one-pass noise estimate is conservative
//!   (a few times the test error in the tests) because the pseudo-targets
//!   `μ_f` of early samples stay in the statistics.
//! * **Targets** are scaled: `fit` centres and scales each output by the
//!   batch's mean and standard deviation; online use without `fit` divides by
//!   `target_scale` (0.01 m/s). Inputs are used as given: the pipeline has
//!   already standardised them.
//!
//! # Timing
//! [`Ilgr::predict_row`] and [`gpodo_traits::ResidualRegressor::update`] are
//! the per-sample calls; the ignored test `per_sample_cost_at_d28` in
//! `tests/ilgr.rs` times them at `d = 28` with three outputs.

pub mod blas;
pub mod gamma;
pub mod local_model;
pub mod model;
pub mod params;
pub mod state;
pub mod weights;

pub use gamma::{GammaPrior, GammaStats};
pub use local_model::LocalModel;
pub use model::Ilgr;
pub use params::IlgrParams;
pub use state::IlgrState;
