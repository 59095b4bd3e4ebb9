//! The sparse-spectrum GP learned online (I-SSGP; Gijsberts & Metta,
//! *Neural Networks* 2013): Bayesian linear regression on `D` random
//! Fourier features of a stationary ARD kernel, whose posterior is kept as
//! the Cholesky factor of its precision and updated by one exact rank-one
//! update per sample, `O(D²)`.
//!
//! With `m = D/2` frequencies `ω_i` drawn from the kernel's spectral density
//! (for RBF `ω = z / ℓ`, `z ~ N(0, I)`; for Matérn ν a Student-t with `2ν`
//! degrees of freedom, `ω = z / ℓ · √(2ν / u)`, `u ~ χ²(2ν)`), the features
//! `φ(x) = √(σ_f² / m) [cos(ωᵢᵀx), sin(ωᵢᵀx)]` satisfy
//! `E[φ(x)ᵀφ(x')] = k(x − x')`. With weights `w ~ N(0, I)` and noise `σ_n²`:
//!
//! With `bias_variance` `σ_b² > 0` a constant feature `σ_b` follows the
//! random ones (the kernel `k + σ_b²`, a constant mean with a Gaussian
//! prior integrated out).
//!
//! * `A = σ_n² I + Σ_t λ^{T−t} φ_t φ_tᵀ`, `b = Σ_t λ^{T−t} φ_t y_t` (the
//!   forgetting `λ` scales both before each update);
//! * mean `φ*ᵀ A⁻¹ b`; latent variance `σ_n² φ*ᵀ A⁻¹ φ*`; noisy variance
//!   `σ_n² (1 + φ*ᵀ A⁻¹ φ*)`.
//!
//! With `learn_noise` the noise variance is learned too, conjugately: the
//! prior is `w | σ² ~ N(0, (σ²/σ_n²) I)` and `σ² ~ IG(a₀, b₀)` with
//! `a₀ = 2`, `b₀ = σ_n²` (prior mean `σ_n²`), so that at `σ² = σ_n²` it is the
//! model above. The posterior keeps `A` and `b`, and adds, per output,
//! `a = a₀ + n/2` and `b_σ = b₀ + ½ (Σ_t λ^{T−t} y_t² − bᵀA⁻¹b)` (`n` the
//! discounted count of rows). A new target is then Student-t with `2a`
//! degrees of freedom, location `φ*ᵀA⁻¹b` and scale² `(b_σ/a)(1 + φ*ᵀA⁻¹φ*)`;
//! its variance, scale² · `2a/(2a − 2)`, is what `predict` reports.
//!
//! As `D → ∞` the mean tends to the exact GP's at the same hyperparameters.
//! The hyperparameters (`σ_f²`, the lengthscales, `σ_n²`) and the input
//! and target scaling come from a batch exact-GP fit on the stream's first
//! `warmup_rows` rows, and never from later rows.

pub mod params;

use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{ChiSquared, Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use gpodo_traits::{
    Error, FitProgress, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
    Standardizer,
};

use crate::RegressorError;
use crate::exact_gp::{ExactGp, ExactGpParams};
use crate::kernels::LeafName;
pub use params::SparseSpectrumParams;

/// Everything needed to predict and go on learning, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SparseSpectrumState {
    /// The settings.
    pub params: SparseSpectrumParams,
    /// Input column names.
    pub input_names: Vec<String>,
    /// Output column names.
    pub target_names: Vec<String>,
    /// The warm-up rows' input scaling (None: inputs used as given).
    pub input_scaler: Option<Standardizer>,
    /// The warm-up rows' target scaling.
    pub output_scaler: Option<Standardizer>,
    /// The frequencies `ωᵢ`, one per row (`D/2 × d`, scaled inputs).
    pub frequencies: SampleMatrix,
    /// Signal variance `σ_f²` (scaled units).
    pub signal_variance: f64,
    /// Noise variance `σ_n²` (scaled units).
    pub noise_variance: f64,
    /// Lower Cholesky factor of `A` (`D × D`).
    pub factor: DMatrix<f64>,
    /// `b` (`D × outputs`).
    pub rhs: DMatrix<f64>,
    /// Rows learned so far.
    pub rows_seen: usize,
    /// The noise variance's posterior, when it is learned.
    #[serde(default)]
    pub noise_posterior: Option<NoisePosterior>,
}

/// The inverse-Gamma posterior of the noise variance `σ²` (scaled units)
/// of a sparse-spectrum GP that learns it: the prior and the discounted
/// statistics of the rows learned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoisePosterior {
    /// Prior shape `a₀`.
    pub prior_shape: f64,
    /// Prior scale `b₀`.
    pub prior_scale: f64,
    /// Rows learned, each discounted by the forgetting factor since.
    pub rows: f64,
    /// Per output, `Σ_t λ^{T−t} y_t²` of the scaled targets.
    pub target_energy: Vec<f64>,
}

/// The noise prior's shape `a₀`: the weakest proper prior whose mean
/// `b₀ / (a₀ − 1)` exists.
const NOISE_PRIOR_SHAPE: f64 = 2.0;

impl NoisePosterior {
    /// The variance of a new scaled target of output `j` whose features
    /// give `φ*ᵀA⁻¹φ* = leverage`, where `b_j ᵀ A⁻¹ b_j = explained`.
    fn predictive_variance(&self, j: usize, explained: f64, leverage: f64) -> f64 {
        let shape = self.prior_shape + 0.5 * self.rows;
        let residual = (self.target_energy[j] - explained).max(0.0);
        let scale = (self.prior_scale + 0.5 * residual) / shape;
        let dof = 2.0 * shape;
        scale * (1.0 + leverage) * dof / (dof - 2.0)
    }
}

/// `L Lᵀ + x xᵀ`, in place: the rank-one update of a lower Cholesky factor
/// by Givens-like rotations, column by column, `O(D²)`. Hand-written
/// because forgetting scales the factor itself, which nalgebra's
/// `Cholesky` (with its own `rank_one_update`) does not expose.
fn rank_one_update(l: &mut DMatrix<f64>, mut x: DVector<f64>) {
    let n = x.len();
    for k in 0..n {
        let lkk = l[(k, k)];
        let r = lkk.hypot(x[k]);
        let (c, s) = (r / lkk, x[k] / lkk);
        l[(k, k)] = r;
        for i in k + 1..n {
            let lik = (l[(i, k)] + s * x[i]) / c;
            l[(i, k)] = lik;
            x[i] = c * x[i] - s * lik;
        }
    }
}

/// The sparse-spectrum GP regressor (`kind: sparse_spectrum`).
///
/// Learning from a stream without a `fit` first, it keeps the first
/// `warmup_rows` rows, predicting their running mean and variance, and then
/// warms up on them and learns on from there.
#[derive(Debug, Clone)]
pub struct SparseSpectrumGp {
    params: SparseSpectrumParams,
    learned: Option<SparseSpectrumState>,
    /// Rows of a stream kept until the warm-up.
    buffer: Vec<(Vec<f64>, Vec<f64>)>,
    progress: crate::hyperopt::ProgressSink,
}

/// How many features a state has: `2m` random ones, and the constant.
fn feature_count(frequencies: usize, bias_variance: f64) -> usize {
    2 * frequencies + usize::from(bias_variance > 0.0)
}

/// The features `φ(x)` of one scaled input row.
fn features(state: &SparseSpectrumState, x: &[f64]) -> DVector<f64> {
    let m = state.frequencies.nrows();
    let scale = (state.signal_variance / m as f64).sqrt();
    let bias = state.params.bias_variance;
    let mut phi = DVector::zeros(feature_count(m, bias));
    for (i, omega) in state.frequencies.rows().enumerate() {
        let angle: f64 = omega.iter().zip(x).map(|(w, v)| w * v).sum();
        let (s, c) = angle.sin_cos();
        phi[i] = scale * c;
        phi[m + i] = scale * s;
    }
    if bias > 0.0 {
        phi[2 * m] = bias.sqrt();
    }
    phi
}

/// `count` frequencies drawn from the spectral density of the kernel `leaf`
/// (rbf, matern52, matern32) with ARD `lengthscales`, from `seed`; one per
/// row.
///
/// # Errors
/// [`RegressorError::InvalidData`] if the density cannot be sampled, or
/// the kernel has none (linear, white, rational quadratic).
pub fn draw_frequencies(
    leaf: LeafName,
    lengthscales: &[f64],
    count: usize,
    seed: u64,
) -> Result<SampleMatrix, RegressorError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nu: Option<f64> = match leaf {
        LeafName::Matern52 => Some(2.5),
        LeafName::Matern32 => Some(1.5),
        LeafName::Rbf => None,
        LeafName::Linear | LeafName::White | LeafName::RatQuad => {
            return Err(RegressorError::InvalidData {
                detail: format!(
                    "sparse_spectrum frequencies: `{leaf}` has no spectral density to sample"
                ),
            });
        }
    };
    let chi = nu
        .map(|nu| ChiSquared::new(2.0 * nu))
        .transpose()
        .map_err(|e| RegressorError::InvalidData {
            detail: format!("sparse_spectrum frequencies: {e}"),
        })?;
    let mut data = Vec::with_capacity(count * lengthscales.len());
    for _ in 0..count {
        let t = match (nu, &chi) {
            (Some(nu), Some(chi)) => {
                let u: f64 = chi.sample(&mut rng);
                (2.0 * nu / u).sqrt()
            }
            _ => 1.0,
        };
        for l in lengthscales {
            let z: f64 = StandardNormal.sample(&mut rng);
            data.push(z * t / l);
        }
    }
    SampleMatrix::from_row_major(count, lengthscales.len(), data).map_err(RegressorError::from)
}

impl SparseSpectrumGp {
    /// A model with checked settings.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bad field.
    pub fn new(params: SparseSpectrumParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            params,
            learned: None,
            buffer: Vec::new(),
            progress: Default::default(),
        })
    }

    /// The learned state (None before `fit`).
    pub fn state(&self) -> Option<&SparseSpectrumState> {
        self.learned.as_ref()
    }

    /// Rebuilds a model from its saved state.
    ///
    /// # Errors
    /// [`RegressorError::InvalidData`] when the state is inconsistent.
    pub fn from_state(state: SparseSpectrumState) -> Result<Self, RegressorError> {
        state.params.check()?;
        let dim = feature_count(state.frequencies.nrows(), state.params.bias_variance);
        let bad = |detail: &str| RegressorError::InvalidData {
            detail: format!("saved sparse_spectrum state: {detail}"),
        };
        if state.factor.shape() != (dim, dim) || state.rhs.nrows() != dim {
            return Err(bad(
                "its factor or right-hand side does not match its features",
            ));
        }
        if (0..dim).any(|k| state.factor[(k, k)].is_nan() || state.factor[(k, k)] <= 0.0) {
            return Err(bad("its factor is not positive definite"));
        }
        if let Some(noise) = &state.noise_posterior
            && (noise.target_energy.len() != state.rhs.ncols()
                || !(noise.prior_shape > 1.0 && noise.prior_scale > 0.0 && noise.rows >= 0.0))
        {
            return Err(bad(
                "its noise posterior does not match its outputs or is not a proper prior",
            ));
        }
        Ok(Self {
            params: state.params.clone(),
            learned: Some(state),
            buffer: Vec::new(),
            progress: Default::default(),
        })
    }

    /// The batch warm-up: an exact GP with the kernel on the first rows.
    fn warm_up(&self, data: &ResidualDataset) -> Result<(ExactGp, FitReport), RegressorError> {
        let rows: Vec<usize> = (0..data.len().min(self.params.warmup_rows)).collect();
        let head = ResidualDataset::new(
            data.inputs.select_rows(&rows),
            data.targets.select_rows(&rows),
            data.input_names.clone(),
            data.target_names.clone(),
        )?
        .with_standardized_inputs(data.inputs_standardized);
        let mut gp = ExactGp::new(ExactGpParams {
            hyperopt: self.params.hyperopt,
            seed: self.params.seed,
            ..ExactGpParams::with_kernel(self.params.kernel.clone())
        })?;
        gp.set_progress(self.progress.0.clone());
        let report = gp.fit(&head)?;
        Ok((gp, report))
    }

    fn fit_impl(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        let start = Instant::now();
        if data.len() < 2 {
            return Err(RegressorError::InvalidData {
                detail: "sparse_spectrum needs at least 2 rows to warm up on".into(),
            });
        }
        let (gp, mut report) = self.warm_up(data)?;
        let Some(gp_state) = gp.state() else {
            return Err(RegressorError::InvalidData {
                detail: "the warm-up GP left no state".into(),
            });
        };
        let group = &gp_state.groups[0];
        let names = group.kernel.param_names(&data.input_names);
        let values: Vec<f64> = group
            .kernel
            .log_params()
            .into_iter()
            .map(f64::exp)
            .collect();
        let mut signal_variance = 1.0;
        let mut lengthscales = Vec::new();
        for (name, value) in names.iter().zip(&values) {
            if name.ends_with(".variance") {
                signal_variance = *value;
            } else if name.contains(".lengthscale[") {
                lengthscales.push(*value);
            }
        }
        let leaf = self.params.leaf().unwrap_or(LeafName::Rbf);
        let frequencies = draw_frequencies(
            leaf,
            &lengthscales,
            self.params.features / 2,
            self.params.seed,
        )?;
        let dim = feature_count(self.params.features / 2, self.params.bias_variance);
        let noise_variance = group.noise_variance;
        if noise_variance.is_nan() || noise_variance <= 0.0 {
            return Err(RegressorError::InvalidData {
                detail: format!("sparse_spectrum: noise variance {noise_variance} is not positive"),
            });
        }
        let mut state = SparseSpectrumState {
            params: self.params.clone(),
            input_names: data.input_names.clone(),
            target_names: data.target_names.clone(),
            input_scaler: gp_state.input_scaler.clone(),
            output_scaler: gp_state.output_scaler.clone(),
            frequencies,
            signal_variance,
            noise_variance,
            // A = σ_n² I before any row.
            factor: DMatrix::identity(dim, dim) * noise_variance.sqrt(),
            rhs: DMatrix::zeros(dim, data.targets.ncols()),
            rows_seen: 0,
            noise_posterior: self.params.learn_noise.then(|| NoisePosterior {
                prior_shape: NOISE_PRIOR_SHAPE,
                prior_scale: (NOISE_PRIOR_SHAPE - 1.0) * noise_variance,
                rows: 0.0,
                target_energy: vec![0.0; data.targets.ncols()],
            }),
        };
        for (x, y) in data.inputs.rows().zip(data.targets.rows()) {
            state.learn(x, y)?;
        }
        self.learned = Some(state);
        report.n_samples = data.len();
        report
            .parameters
            .push(("features".into(), self.params.features as f64));
        report.duration_secs = start.elapsed().as_secs_f64();
        Ok(report)
    }
}

/// A raw row z-scored by `scaler` (as given without one).
fn scale_row(scaler: &Option<Standardizer>, v: &[f64]) -> Vec<f64> {
    match scaler {
        Some(s) => v
            .iter()
            .zip(s.mean.iter().zip(&s.std))
            .map(|(v, (m, sd))| (v - m) / sd)
            .collect(),
        None => v.to_vec(),
    }
}

impl SparseSpectrumState {
    /// One exact rank-one update with the pair `(x, y)` (raw units).
    fn learn(&mut self, x: &[f64], y: &[f64]) -> Result<(), Error> {
        let (d, p) = (self.frequencies.ncols(), self.rhs.ncols());
        if x.len() != d || y.len() != p {
            return Err(Error::DimensionMismatch {
                what: "sparse_spectrum inputs and targets".into(),
                expected: d + p,
                found: x.len() + y.len(),
            });
        }
        if x.iter().chain(y).any(|v| !v.is_finite()) {
            return Err(Error::InvalidInput(
                "sparse_spectrum: a non-finite input or target".into(),
            ));
        }
        let phi = features(self, &scale_row(&self.input_scaler, x));
        let ys = scale_row(&self.output_scaler, y);
        let lambda = self.params.forgetting;
        if lambda < 1.0 {
            // A ← λA and b ← λb: the factor scales by √λ.
            self.factor *= lambda.sqrt();
            self.rhs *= lambda;
        }
        for (j, t) in ys.iter().enumerate() {
            self.rhs.column_mut(j).axpy(*t, &phi, 1.0);
        }
        if let Some(noise) = &mut self.noise_posterior {
            noise.rows = lambda * noise.rows + 1.0;
            for (e, t) in noise.target_energy.iter_mut().zip(&ys) {
                *e = lambda * *e + t * t;
            }
        }
        rank_one_update(&mut self.factor, phi);
        self.rows_seen += 1;
        Ok(())
    }
}

impl SparseSpectrumGp {
    /// A stream's row before the warm-up: kept, and once there are
    /// `warmup_rows` of them, warmed up on and learned.
    fn keep_for_warm_up(&mut self, x: &[f64], y: &[f64]) -> Result<(), Error> {
        if let Some((x0, y0)) = self.buffer.first()
            && (x0.len() != x.len() || y0.len() != y.len())
        {
            return Err(Error::DimensionMismatch {
                what: "sparse_spectrum inputs and targets".into(),
                expected: x0.len() + y0.len(),
                found: x.len() + y.len(),
            });
        }
        self.buffer.push((x.to_vec(), y.to_vec()));
        if self.buffer.len() < self.params.warmup_rows {
            return Ok(());
        }
        let rows = std::mem::take(&mut self.buffer);
        let data = crate::stream_rows::rows_dataset(&rows)?;
        self.fit_impl(&data).map(|_| ()).map_err(Error::from)
    }

    /// Before the warm-up: the kept rows' mean and variance per output (an
    /// error before any row).
    fn predict_before_warm_up(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        crate::stream_rows::running_moments(self.name(), &self.buffer, inputs)
    }
}

impl ResidualRegressor for SparseSpectrumGp {
    fn name(&self) -> &str {
        "sparse_spectrum"
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        self.fit_impl(data).map_err(Error::from)
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let Some(state) = &self.learned else {
            return self.predict_before_warm_up(inputs);
        };
        let d = state.frequencies.ncols();
        if inputs.ncols() != d {
            return Err(Error::DimensionMismatch {
                what: "sparse_spectrum input columns".into(),
                expected: d,
                found: inputs.ncols(),
            });
        }
        let p = state.rhs.ncols();
        let singular = || Error::Numerical {
            context: "sparse_spectrum prediction".into(),
            detail: "its Cholesky factor is singular".into(),
        };
        // w = A⁻¹ b = L⁻ᵀ (L⁻¹ b).
        let half = state
            .factor
            .solve_lower_triangular(&state.rhs)
            .ok_or_else(singular)?;
        let weights = state
            .factor
            .tr_solve_lower_triangular(&half)
            .ok_or_else(singular)?;
        // bᵀA⁻¹b per output, the fit's explained energy.
        let explained: Vec<f64> = (0..p)
            .map(|j| state.rhs.column(j).dot(&weights.column(j)))
            .collect();
        let mut mean = Vec::with_capacity(inputs.nrows() * p);
        let mut variance = Vec::with_capacity(inputs.nrows() * p);
        for x in inputs.rows() {
            let phi = features(state, &scale_row(&state.input_scaler, x));
            let v = state
                .factor
                .solve_lower_triangular(&phi)
                .ok_or_else(singular)?;
            let leverage = v.norm_squared();
            for (j, explained) in explained.iter().enumerate() {
                let m = phi.dot(&weights.column(j));
                let (mu, sd) = state
                    .output_scaler
                    .as_ref()
                    .map_or((0.0, 1.0), |s| (s.mean[j], s.std[j]));
                let noisy = match &state.noise_posterior {
                    Some(noise) => noise.predictive_variance(j, *explained, leverage),
                    None => state.noise_variance * (1.0 + leverage),
                };
                mean.push(m * sd + mu);
                variance.push(noisy * sd * sd);
            }
        }
        Ok(Predictions {
            mean: SampleMatrix::from_row_major(inputs.nrows(), p, mean)?,
            variance: SampleMatrix::from_row_major(inputs.nrows(), p, variance)?,
        })
    }

    fn set_progress(&mut self, progress: Option<std::sync::Arc<dyn FitProgress>>) {
        self.progress = crate::hyperopt::ProgressSink(progress);
    }

    fn supports_online_update(&self) -> bool {
        true
    }

    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        let Some(state) = &mut self.learned else {
            return self.keep_for_warm_up(inputs, targets);
        };
        state.learn(inputs, targets)
    }
}
