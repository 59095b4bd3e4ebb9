//! [`SparseGp`] behind [`ResidualRegressor`]: standardises like the exact
//! GP, places the inducing inputs, learns hyperparameters (and the inducing
//! inputs unless fixed) on the VFE bound or the FITC likelihood, and keeps
//! only the `O(m²)` posterior. A trained model round-trips through
//! [`SparseGpState`] (serde) without the training data.

use std::time::Instant;

use faer::{Mat, MatRef};
use gpodo_traits::Standardizer;
use gpodo_traits::{
    Error, FitReport, ResidualDataset, ResidualRegressor, SampleMatrix, StartRecord,
};
use serde::{Deserialize, Serialize};

use super::bound::sparse_objective;
use super::inducing::place_inducing;
use super::params::{Approximation, SparseGpParams};
use super::posterior::SparsePosterior;
use crate::dense::{from_faer, to_faer};
use crate::hyperopt::{HyperProblem, Objective, ProgressSink, SearchSpace, learn, starts};
use crate::kernels::Kernel;
use crate::scaling::{GpPredictions, ScaledTraining, check_finite};
use crate::{GpProblem, RegressorError, SparseProblem};

/// Everything needed to predict with a trained sparse GP: `O(m²)` numbers,
/// no training data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SparseGpState {
    /// The settings it was trained with.
    pub params: SparseGpParams,
    /// Input column names.
    pub input_names: Vec<String>,
    /// Output column names.
    pub target_names: Vec<String>,
    /// Input scaling (None when `standardize` is off).
    pub input_scaler: Option<Standardizer>,
    /// Output scaling (None when `standardize` is off).
    pub output_scaler: Option<Standardizer>,
    /// Kernel with learned hyperparameters (standardised units).
    pub kernel: Kernel,
    /// Learned noise variance (standardised units).
    pub noise_variance: f64,
    /// Inducing inputs `Z` (`m × d`, standardised units).
    pub inducing: SampleMatrix,
    /// `β` (`m × p`).
    pub weights: SampleMatrix,
    /// `P = K_uu⁻¹ − Σ⁻¹` (`m × m`).
    pub variance_matrix: SampleMatrix,
    /// The training objective (bound or FITC likelihood).
    pub objective: f64,
}

/// A kernel, a noise variance and the inducing inputs.
type Hyperparameters = (Kernel, f64, Mat<f64>);

/// What learning the hyperparameters cost, for the fit report (empty
/// when they were not learned).
#[derive(Debug, Default)]
struct Learned {
    evaluations: Option<usize>,
    iterations: Option<u64>,
    starts: Vec<StartRecord>,
}

/// The learned hyperparameters by name, then the noise variance and the
/// number of inducing points.
fn learned_parameters(posterior: &SparsePosterior, input_names: &[String]) -> Vec<(String, f64)> {
    let kernel = &posterior.kernel;
    let mut parameters: Vec<(String, f64)> = kernel
        .param_names(input_names)
        .into_iter()
        .zip(kernel.log_params().into_iter().map(f64::exp))
        .collect();
    parameters.push(("noise_variance".into(), posterior.noise_variance));
    parameters.push(("inducing_points".into(), posterior.inducing.nrows() as f64));
    parameters
}

/// The sparse Gaussian process regressor.
#[derive(Debug, Clone)]
pub struct SparseGp {
    params: SparseGpParams,
    fitted: Option<(SparseGpState, SparsePosterior)>,
    progress: ProgressSink,
}

/// The objective over `(log θ, log σ², Z)` (Z only when learned).
struct SparseObjective<'a> {
    template: &'a Kernel,
    x: MatRef<'a, f64>,
    y: MatRef<'a, f64>,
    inducing: &'a Mat<f64>,
    learn_inducing: bool,
    approximation: Approximation,
    jitter: f64,
}

impl SparseObjective<'_> {
    fn unpack(&self, coords: &[f64]) -> Hyperparameters {
        let k = self.template.n_params();
        let mut kernel = self.template.clone();
        kernel.set_log_params(&coords[..k]);
        let (m, d) = (self.inducing.nrows(), self.inducing.ncols());
        let z = if self.learn_inducing {
            Mat::from_fn(m, d, |i, q| coords[k + 1 + i * d + q])
        } else {
            self.inducing.clone()
        };
        (kernel, coords[k].exp(), z)
    }
}

impl Objective for SparseObjective<'_> {
    fn evaluate(&self, coords: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        let (kernel, noise, z) = self.unpack(coords);
        let problem = SparseProblem {
            gp: GpProblem::new(&kernel, noise, self.x, self.y),
            z: z.as_ref(),
            approximation: self.approximation,
            jitter: self.jitter,
        };
        let eval = sparse_objective(problem, true, self.learn_inducing)?;
        let mut gradient = eval.gradient.unwrap_or_default();
        if let Some(dz) = eval.inducing_gradient {
            for i in 0..dz.nrows() {
                gradient.extend((0..dz.ncols()).map(|q| dz[(i, q)]));
            }
        }
        Ok((eval.value, gradient))
    }
}

impl SparseGp {
    /// A sparse GP with checked settings.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bad field.
    pub fn new(params: SparseGpParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            params,
            fitted: None,
            progress: ProgressSink::default(),
        })
    }

    /// The settings.
    pub fn params(&self) -> &SparseGpParams {
        &self.params
    }

    /// The trained model as serialisable state (None before `fit`).
    pub fn state(&self) -> Option<&SparseGpState> {
        self.fitted.as_ref().map(|(s, _)| s)
    }

    /// Rebuilds a trained sparse GP from its state (no refit, no data).
    ///
    /// # Errors
    /// As [`SparseGpParams::check`], or when the state's shapes disagree or
    /// hold non-finite values.
    pub fn from_state(state: SparseGpState) -> Result<Self, RegressorError> {
        state.params.check()?;
        for (what, m) in [
            ("saved inducing inputs", &state.inducing),
            ("saved weights", &state.weights),
            ("saved variance matrix", &state.variance_matrix),
        ] {
            check_finite(what, m)?;
        }
        let m = state.inducing.nrows();
        let consistent = state.weights.nrows() == m
            && state.variance_matrix.nrows() == m
            && state.variance_matrix.ncols() == m
            && state
                .kernel
                .input_dim()
                .is_none_or(|d| d == state.inducing.ncols());
        if !consistent {
            return Err(RegressorError::InvalidData {
                detail: "saved sparse GP state: inducing inputs, weights, variance matrix and kernel width disagree".into(),
            });
        }
        let posterior = SparsePosterior {
            kernel: state.kernel.clone(),
            noise_variance: state.noise_variance,
            inducing: to_faer(&state.inducing),
            weights: to_faer(&state.weights),
            variance_matrix: to_faer(&state.variance_matrix),
            objective: state.objective,
            extra_jitter: 0.0,
        };
        Ok(Self {
            params: state.params.clone(),
            fitted: Some((state, posterior)),
            progress: ProgressSink::default(),
        })
    }

    fn fit_impl(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        let start = Instant::now();
        let scaled = ScaledTraining::new(data, self.params.standardize)?;
        let (x, y) = (to_faer(&scaled.x), to_faer(&scaled.y));
        let p = &self.params;
        if p.inducing.count > x.nrows() {
            tracing::warn!(
                asked = p.inducing.count,
                used = x.nrows(),
                "more inducing points asked than training rows: every row is one"
            );
        }
        let z0 = place_inducing(x.as_ref(), &p.inducing, p.seed);
        let kernel0 = p.kernel.build(x.ncols(), &p.init);
        let objective = SparseObjective {
            template: &kernel0,
            x: x.as_ref(),
            y: y.as_ref(),
            inducing: &z0,
            learn_inducing: p.optimize && !p.inducing.fixed,
            approximation: p.approximation,
            jitter: p.jitter,
        };
        let ((kernel, noise, z), learned) = if p.optimize {
            self.learn(&objective)?
        } else {
            (
                (kernel0.clone(), p.noise_variance, z0.clone()),
                Learned::default(),
            )
        };
        let posterior = SparsePosterior::new(SparseProblem {
            gp: GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
            z: z.as_ref(),
            approximation: p.approximation,
            jitter: p.jitter,
        })?;
        let report = FitReport {
            n_samples: data.len(),
            duration_secs: start.elapsed().as_secs_f64(),
            objective: Some(posterior.objective),
            evaluations: learned.evaluations,
            jitter: Some(p.jitter + posterior.extra_jitter),
            parameters: learned_parameters(&posterior, &data.input_names),
            iterations: learned.iterations,
            starts: learned.starts,
            ..FitReport::default()
        };
        let state = SparseGpState {
            params: self.params.clone(),
            input_names: data.input_names.clone(),
            target_names: data.target_names.clone(),
            input_scaler: scaled.input_scaler,
            output_scaler: scaled.output_scaler,
            kernel: posterior.kernel.clone(),
            noise_variance: posterior.noise_variance,
            inducing: from_faer(posterior.inducing.as_ref()),
            weights: from_faer(posterior.weights.as_ref()),
            variance_matrix: from_faer(posterior.variance_matrix.as_ref()),
            objective: posterior.objective,
        };
        self.fitted = Some((state, posterior));
        Ok(report)
    }

    /// Learns the hyperparameters (and the inducing inputs unless fixed)
    /// with the GPs' recipe, from the kernel's base starts with the placed
    /// inducing inputs.
    fn learn(
        &self,
        objective: &SparseObjective<'_>,
    ) -> Result<(Hyperparameters, Learned), RegressorError> {
        let p = &self.params;
        let z0 = objective.inducing;
        let inducing: Vec<f64> = if objective.learn_inducing {
            (0..z0.nrows())
                .flat_map(|i| (0..z0.ncols()).map(move |q| z0[(i, q)]))
                .collect()
        } else {
            Vec::new()
        };
        let bases = starts::kernel_bases(&p.kernel, &p.init, objective.x, p.noise_variance)
            .into_iter()
            .map(|(label, mut c)| {
                c.extend_from_slice(&inducing);
                (label, c)
            })
            .collect();
        let score = |c: &[f64]| objective.evaluate(c).map(|(v, _)| v);
        let problem = HyperProblem {
            objective,
            score: &score,
            space: SearchSpace::kernel(objective.template, &p.hyperopt.bounds)
                .with_free(inducing.len()),
            bases,
            value_scale: 1.0 / (objective.y.nrows() * objective.y.ncols()) as f64,
        };
        let (out, starts) = learn(&problem, &p.hyperopt, p.seed, &self.progress)?;
        tracing::debug!(
            objective = out.value,
            evaluations = out.evaluations,
            iterations = out.iterations,
            "sparse GP hyperparameters learned"
        );
        let learned = Learned {
            evaluations: Some(out.evaluations),
            iterations: Some(out.iterations),
            starts,
        };
        Ok((objective.unpack(&out.coords), learned))
    }

    /// Mean, latent variance and noisy variance at `inputs`, in target units.
    ///
    /// # Errors
    /// [`Error::NotFitted`] before `fit`; [`Error::DimensionMismatch`] for a
    /// wrong input width; [`Error::InvalidInput`] for non-finite inputs.
    pub fn predict_full(&self, inputs: &SampleMatrix) -> Result<GpPredictions, Error> {
        let Some((state, posterior)) = &self.fitted else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        posterior.predict_scaled(
            self.name(),
            inputs,
            state.inducing.ncols(),
            state.input_scaler.as_ref(),
            state.output_scaler.as_ref(),
        )
    }
}

crate::scaling::gp_residual_regressor!(SparseGp, "sparse_gp");
