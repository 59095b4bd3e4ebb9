//! [`ExactGp`]: the exact GP regressor of the paper (§IV-A), behind
//! [`ResidualRegressor`]. Standardises inputs and outputs with training
//! statistics, learns hyperparameters per output group (all outputs
//! sharing one kernel, or one GP per output), and predicts means and
//! variances mapped back to target units (variance × std²). A trained model
//! round-trips through [`ExactGpState`] (serde) for on-board prediction.

use std::time::Instant;

use faer::Mat;
use gpodo_traits::Standardizer;
use gpodo_traits::{Error, FitReport, ResidualDataset, ResidualRegressor, SampleMatrix};
use serde::{Deserialize, Serialize};

use super::choice::KernelChoice;
use super::iterative::IterativeSolver;
use super::optimize::{conditions_iteratively, maximize_lml};
use super::params::{ExactGpParams, OutputSharing};
use super::posterior::Posterior;
use crate::RegressorError;
use crate::dense::to_faer;
use crate::hyperopt::ProgressSink;
use crate::kernels::Kernel;
use crate::scaling::{
    GpPredictions, ScaledTraining, check_finite, scale_queries, unscale_predictions,
};

/// Conditions the GP of `params` with `kernel` and `noise_variance` on
/// `(x, y)`: by iterative solves where its hyperparameters are learned so
/// ([`conditions_iteratively`]), else by a dense factor.
///
/// # Errors
/// [`RegressorError::NotPositiveDefinite`] when `K_y` cannot be factorised
/// or CG breaks down.
fn condition(
    params: &ExactGpParams,
    kernel: Kernel,
    noise_variance: f64,
    x: Mat<f64>,
    y: Mat<f64>,
) -> Result<Posterior, RegressorError> {
    let n = x.nrows();
    if conditions_iteratively(params, n, noise_variance) {
        let solver = IterativeSolver::new(n, params.iterative);
        let _spare = crate::dense::SpareLimit::at_least(3 * n * n * std::mem::size_of::<f64>());
        let posterior = Posterior::iterative(
            kernel,
            noise_variance,
            x,
            y,
            &solver,
            params.iterative.variance_rank,
        );
        crate::dense::release_spare();
        posterior
    } else {
        Posterior::new(kernel, noise_variance, x, y)
    }
}

/// The standard error (nats) of an iterative likelihood estimate above
/// which a fit warns that its optimum may be off: the optimiser's line
/// searches compare values a few nats apart.
const UNRELIABLE_ESTIMATE_NATS: f64 = 1.0;

/// One output group's learned model, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupState {
    /// The output columns this GP predicts.
    pub outputs: Vec<usize>,
    /// Kernel with learned hyperparameters (standardised units).
    pub kernel: Kernel,
    /// Learned noise variance (standardised units).
    pub noise_variance: f64,
}

/// Everything needed to rebuild a trained exact GP without refitting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExactGpState {
    /// The settings it was trained with.
    pub params: ExactGpParams,
    /// Input column names.
    pub input_names: Vec<String>,
    /// Output column names.
    pub target_names: Vec<String>,
    /// Input scaling (None when `standardize` is off).
    pub input_scaler: Option<Standardizer>,
    /// Output scaling (None when `standardize` is off).
    pub output_scaler: Option<Standardizer>,
    /// Training inputs after scaling.
    pub x_train: SampleMatrix,
    /// Training targets after scaling.
    pub y_train: SampleMatrix,
    /// One entry per output group.
    pub groups: Vec<GroupState>,
}

#[derive(Debug, Clone)]
struct Fitted {
    state: ExactGpState,
    posteriors: Vec<Posterior>,
}

/// The exact Gaussian process regressor.
#[derive(Debug, Clone)]
pub struct ExactGp {
    params: ExactGpParams,
    fitted: Option<Fitted>,
    progress: ProgressSink,
    /// Per output group, the coordinates `(log θ, log σ_n²)` the next fit
    /// starts from alone ([`ExactGp::warm_start_from`]).
    warm: Option<Vec<Vec<f64>>>,
}

fn columns(m: &Mat<f64>, cols: &[usize]) -> Mat<f64> {
    Mat::from_fn(m.nrows(), cols.len(), |i, j| m[(i, cols[j])])
}

impl ExactGp {
    /// A GP with checked settings.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bad field.
    pub fn new(params: ExactGpParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            params,
            fitted: None,
            progress: ProgressSink::default(),
            warm: None,
        })
    }

    /// The settings.
    pub fn params(&self) -> &ExactGpParams {
        &self.params
    }

    /// The trained model as serialisable state (None before `fit`).
    pub fn state(&self) -> Option<&ExactGpState> {
        self.fitted.as_ref().map(|f| &f.state)
    }

    /// Log marginal likelihood of each output group (standardised units).
    pub fn log_marginal_likelihoods(&self) -> Vec<f64> {
        self.fitted
            .as_ref()
            .map(|f| f.posteriors.iter().map(|p| p.lml).collect())
            .unwrap_or_default()
    }

    /// Rebuilds a trained GP from its state (one factorisation per group).
    ///
    /// # Errors
    /// As [`ExactGpParams::check`], or when the state is inconsistent or its
    /// kernel matrix cannot be factorised.
    pub fn from_state(state: ExactGpState) -> Result<Self, RegressorError> {
        state.params.check()?;
        check_finite("saved x_train", &state.x_train)?;
        check_finite("saved y_train", &state.y_train)?;
        let x = to_faer(&state.x_train);
        let y = to_faer(&state.y_train);
        let mut posteriors = Vec::with_capacity(state.groups.len());
        for g in &state.groups {
            if g.outputs.iter().any(|&c| c >= y.ncols())
                || g.kernel.input_dim().is_some_and(|d| d != x.ncols())
            {
                return Err(RegressorError::InvalidData {
                    detail: "saved GP state: a group's outputs or kernel width do not match the training data".into(),
                });
            }
            posteriors.push(condition(
                &state.params,
                g.kernel.clone(),
                g.noise_variance,
                x.clone(),
                columns(&y, &g.outputs),
            )?);
        }
        Ok(Self {
            params: state.params.clone(),
            fitted: Some(Fitted { state, posteriors }),
            progress: ProgressSink::default(),
            warm: None,
        })
    }

    /// Makes the next fit start from `previous`'s learned hyperparameters
    /// alone (a warm start, as when refitting on a longer prefix of a
    /// stream), instead of racing the start policy's candidates. It is
    /// cheap, but it keeps to that optimum's basin: on the ExoTeR table's
    /// prefixes the warm start alone kept to a lower optimum on five of
    /// eight refits, by 2.4 to 115.9 nats (`docs/results-log.md`, the
    /// online track of 2026-11-26).
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] when `previous` was fitted with
    /// another kernel expression or output sharing, or when this GP's
    /// kernel is `auto` (each candidate would need its own start).
    pub fn warm_start_from(&mut self, previous: &ExactGpState) -> Result<(), RegressorError> {
        let mismatch = |expected: &str| RegressorError::InvalidSpec {
            regressor: "exact_gp".into(),
            field: "kernel".into(),
            expected: expected.into(),
        };
        if self.params.kernel == KernelChoice::Auto {
            return Err(mismatch(
                "a kernel expression to warm-start (`auto` fits several kernels)",
            ));
        }
        if previous.params.kernel != self.params.kernel
            || previous.params.outputs != self.params.outputs
        {
            return Err(mismatch(
                "the same kernel and output sharing as the model it warm-starts from",
            ));
        }
        let coords = previous
            .groups
            .iter()
            .map(|g| {
                let mut coords = g.kernel.log_params();
                coords.push(g.noise_variance.ln());
                coords
            })
            .collect();
        self.warm = Some(coords);
        Ok(())
    }

    /// `kernel: auto`: every candidate fitted on the same data, the one of
    /// highest log marginal likelihood kept (its settings record the
    /// winner); the report lists every candidate's LML and counts the
    /// evaluations and time of all of them.
    fn fit_auto(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        let start = Instant::now();
        let mut best: Option<(ExactGp, FitReport)> = None;
        let mut tried = Vec::new();
        let mut evaluations = 0;
        for candidate in &self.params.kernel_candidates {
            let mut params = self.params.clone();
            params.kernel = KernelChoice::Expr(candidate.clone());
            let mut gp = ExactGp::new(params)?;
            gp.progress = self.progress.clone();
            let report = gp.fit_impl(data)?;
            let lml = report.objective.unwrap_or(f64::NEG_INFINITY);
            tracing::debug!(kernel = %candidate, lml, "kernel: auto candidate fitted");
            tried.push((candidate.to_string(), lml));
            evaluations += report.evaluations.unwrap_or(0);
            if best
                .as_ref()
                .is_none_or(|(_, b)| lml > b.objective.unwrap_or(f64::NEG_INFINITY))
            {
                best = Some((gp, report));
            }
        }
        let Some((gp, mut report)) = best else {
            return Err(RegressorError::InvalidSpec {
                regressor: "exact_gp".into(),
                field: "kernel_candidates".into(),
                expected: "at least one kernel for `kernel: auto` to try".into(),
            });
        };
        self.fitted = gp.fitted;
        report.kernel_candidates = tried;
        report.evaluations = Some(evaluations);
        report.duration_secs = start.elapsed().as_secs_f64();
        Ok(report)
    }

    fn fit_impl(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        if self.params.kernel == KernelChoice::Auto {
            return self.fit_auto(data);
        }
        let start = Instant::now();
        let (n, d, p) = (data.len(), data.inputs.ncols(), data.targets.ncols());
        let ScaledTraining {
            input_scaler,
            output_scaler,
            x: xs,
            y: ys,
        } = ScaledTraining::new(data, self.params.standardize)?;
        let x = to_faer(&xs);
        let y = to_faer(&ys);
        let group_outputs: Vec<Vec<usize>> = match self.params.outputs {
            OutputSharing::Shared => vec![(0..p).collect()],
            OutputSharing::Independent => (0..p).map(|c| vec![c]).collect(),
        };
        let mut report = FitReport {
            n_samples: n,
            ..Default::default()
        };
        let (mut objective, mut evaluations, mut iterations, mut jitter) = (0.0, 0, 0, 0.0f64);
        let mut groups = Vec::new();
        let mut posteriors = Vec::new();
        for (g, outputs) in group_outputs.into_iter().enumerate() {
            let yg = columns(&y, &outputs);
            let kernel0 = self.params.kernel_expr().build(d, &self.params.init);
            let (kernel, noise) = if self.params.optimize {
                let mut params = self.params.clone();
                params.seed = params.seed.wrapping_add(g as u64);
                let warm = self.warm.as_ref().and_then(|w| w.get(g)).map(Vec::as_slice);
                let opt = maximize_lml(x.as_ref(), yg.as_ref(), &params, &self.progress, warm)?;
                evaluations += opt.evaluations;
                iterations += opt.iterations;
                let group_prefix = match self.params.outputs {
                    OutputSharing::Shared => String::new(),
                    OutputSharing::Independent => format!(
                        "{}: ",
                        data.target_names
                            .get(outputs[0])
                            .cloned()
                            .unwrap_or_default()
                    ),
                };
                report.starts.extend(opt.starts.into_iter().map(|mut s| {
                    s.label = format!("{group_prefix}{}", s.label);
                    s
                }));
                tracing::debug!(
                    group = g,
                    lml = opt.lml,
                    evaluations = opt.evaluations,
                    iterations = opt.iterations,
                    "exact GP hyperparameters learned"
                );
                (opt.kernel, opt.noise_variance)
            } else {
                (kernel0, self.params.noise_variance)
            };
            let posterior = condition(&self.params, kernel.clone(), noise, x.clone(), yg)?;
            if let Some(standard_error) = posterior.lml_standard_error {
                tracing::debug!(
                    estimate = posterior.lml,
                    standard_error,
                    "iterative estimate of the log marginal likelihood at the optimum"
                );
                if standard_error > UNRELIABLE_ESTIMATE_NATS {
                    tracing::warn!(
                        standard_error,
                        "the iterative likelihood estimate has a standard error of {standard_error:.1} nats at the fit's optimum, where the optimiser compared values nats apart: the hyperparameters may be off; `solver: dense`, or more `iterative.probes` (the error falls as one over their square root)"
                    );
                }
            }
            objective += posterior.lml;
            jitter = jitter.max(posterior.jitter());
            let prefix = if matches!(self.params.outputs, OutputSharing::Independent) {
                format!(
                    "{}.",
                    data.target_names
                        .get(outputs[0])
                        .cloned()
                        .unwrap_or_default()
                )
            } else {
                String::new()
            };
            let names = kernel.param_names(&data.input_names);
            let values = kernel.log_params().into_iter().map(f64::exp);
            report.parameters.extend(
                names
                    .into_iter()
                    .zip(values)
                    .map(|(k, v)| (format!("{prefix}{k}"), v)),
            );
            report
                .parameters
                .push((format!("{prefix}noise_variance"), noise));
            groups.push(GroupState {
                outputs,
                kernel,
                noise_variance: noise,
            });
            posteriors.push(posterior);
        }
        report.objective = Some(objective);
        report.evaluations = self.params.optimize.then_some(evaluations);
        report.iterations = self.params.optimize.then_some(iterations);
        report.jitter = Some(jitter);
        report.duration_secs = start.elapsed().as_secs_f64();
        self.fitted = Some(Fitted {
            state: ExactGpState {
                params: self.params.clone(),
                input_names: data.input_names.clone(),
                target_names: data.target_names.clone(),
                input_scaler,
                output_scaler,
                x_train: xs,
                y_train: ys,
                groups,
            },
            posteriors,
        });
        Ok(report)
    }

    /// Mean, latent variance and noisy variance at `inputs`, in target units.
    ///
    /// # Errors
    /// [`Error::NotFitted`] before `fit`; [`Error::DimensionMismatch`] for a
    /// wrong input width; [`Error::InvalidInput`] for non-finite inputs.
    pub fn predict_full(&self, inputs: &SampleMatrix) -> Result<GpPredictions, Error> {
        let Some(fitted) = &self.fitted else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        let state = &fitted.state;
        let xs = scale_queries(
            self.name(),
            inputs,
            state.x_train.ncols(),
            state.input_scaler.as_ref(),
        )?;
        let (m, p) = (xs.nrows(), state.y_train.ncols());
        let mut mean = Mat::<f64>::zeros(m, p);
        let mut latent = Mat::<f64>::zeros(m, p);
        let mut noisy = Mat::<f64>::zeros(m, p);
        for (g, posterior) in state.groups.iter().zip(&fitted.posteriors) {
            let moments = posterior.predict(xs.as_ref());
            for (k, &c) in g.outputs.iter().enumerate() {
                for i in 0..m {
                    mean[(i, c)] = moments.mean[(i, k)];
                    latent[(i, c)] = moments.latent_variance[i];
                    noisy[(i, c)] = moments.latent_variance[i] + moments.noise_variance;
                }
            }
        }
        unscale_predictions(
            mean.as_ref(),
            latent.as_ref(),
            noisy.as_ref(),
            state.output_scaler.as_ref(),
        )
    }
}

crate::scaling::gp_residual_regressor!(ExactGp, "exact_gp");
