//! The residual regressor interface (paper §IV): learns
//! `y_k = s(k+1) − s(k) − g(s(k), u̇(k))` from inputs `x_k` and predicts its
//! mean and variance.

use serde::{Deserialize, Serialize};

use crate::{Error, SampleMatrix};

/// Inputs and residual targets, one row per sample, with column names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualDataset {
    /// `n × d` inputs.
    pub inputs: SampleMatrix,
    /// `n × o` targets (residuals).
    pub targets: SampleMatrix,
    /// Names of the `d` input columns.
    pub input_names: Vec<String>,
    /// Names of the `o` target columns.
    pub target_names: Vec<String>,
    /// Whether `inputs` are already z-scored (an experiment z-scores every
    /// regressor's inputs once, with a [`Standardizer`](crate::Standardizer)
    /// fitted on its training rows): a regressor that z-scores its inputs
    /// leaves these as they are, so the standardisation is done once.
    #[serde(default)]
    pub inputs_standardized: bool,
}

impl ResidualDataset {
    /// Builds a dataset, checking that shapes and names agree.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] naming what disagrees.
    pub fn new(
        inputs: SampleMatrix,
        targets: SampleMatrix,
        input_names: Vec<String>,
        target_names: Vec<String>,
    ) -> Result<Self, Error> {
        let checks = [
            ("target rows", inputs.nrows(), targets.nrows()),
            ("input names", inputs.ncols(), input_names.len()),
            ("target names", targets.ncols(), target_names.len()),
        ];
        for (what, expected, found) in checks {
            if expected != found {
                return Err(Error::DimensionMismatch {
                    what: what.to_string(),
                    expected,
                    found,
                });
            }
        }
        Ok(Self {
            inputs,
            targets,
            input_names,
            target_names,
            inputs_standardized: false,
        })
    }

    /// The same rows, marked as having z-scored inputs
    /// ([`ResidualDataset::inputs_standardized`]).
    #[must_use]
    pub fn with_standardized_inputs(mut self, standardized: bool) -> Self {
        self.inputs_standardized = standardized;
        self
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.inputs.nrows()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The samples with the given indices, in that order.
    pub fn select(&self, indices: &[usize]) -> Self {
        Self {
            inputs: self.inputs.select_rows(indices),
            targets: self.targets.select_rows(indices),
            input_names: self.input_names.clone(),
            target_names: self.target_names.clone(),
            inputs_standardized: self.inputs_standardized,
        }
    }
}

/// Predictive mean and variance, `n × o` each, in target units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Predictions {
    /// Predictive mean.
    pub mean: SampleMatrix,
    /// Predictive variance of the noisy target (latent variance plus noise).
    pub variance: SampleMatrix,
}

/// What a fit did, for reports and reproducibility.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FitReport {
    /// Number of training samples.
    pub n_samples: usize,
    /// Wall-clock duration of the fit (s).
    pub duration_secs: f64,
    /// Final value of the objective the fit optimised, if any
    /// (e.g. the log marginal likelihood).
    pub objective: Option<f64>,
    /// Objective evaluations the optimiser used, if any.
    pub evaluations: Option<usize>,
    /// Diagonal jitter added to make a factorisation succeed, if any.
    pub jitter: Option<f64>,
    /// Learned hyperparameters by name (e.g. `rbf.lengthscale[pitch]`), in
    /// natural units; empty for models without any.
    #[serde(default)]
    pub parameters: Vec<(String, f64)>,
    /// Optimiser iterations, if any.
    #[serde(default)]
    pub iterations: Option<u64>,
    /// Every candidate start the optimiser considered, with its objective
    /// there and, for the starts it ran from, where it ended (shows how
    /// multimodal the problem was); empty for models without an optimiser.
    #[serde(default)]
    pub starts: Vec<StartRecord>,
    /// The kernels a kernel search tried (an exact GP's `kernel: auto`),
    /// each with its log marginal likelihood; the highest was kept. Empty
    /// without a search.
    #[serde(default)]
    pub kernel_candidates: Vec<(String, f64)>,
}

/// One candidate start of a fit's optimiser.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StartRecord {
    /// Which start, e.g. `lengthscale 1` or `lengthscale √D, perturbed #1`
    /// (prefixed by the output group when groups are fitted apart).
    pub label: String,
    /// The objective at the start (`None`: it could not be evaluated).
    pub start_objective: Option<f64>,
    /// The objective where the optimiser ended from this start (`None`:
    /// the optimiser did not run from it).
    pub final_objective: Option<f64>,
    /// Objective evaluations of the optimiser's run from this start.
    #[serde(default)]
    pub evaluations: Option<usize>,
    /// Iterations of the optimiser's run from this start.
    #[serde(default)]
    pub iterations: Option<u64>,
}

/// Receives a fit's progress: the optimiser's iterations (for progress
/// bars and logs; a fit that goes on never depends on it), and may stop the
/// fit.
pub trait FitProgress: Send + Sync {
    /// Iteration `iteration` of start `start` ended with the best objective
    /// `objective` so far (e.g. the log marginal likelihood).
    /// `ControlFlow::Break(())` stops the fit: it returns an error saying
    /// so, never a half-fitted model.
    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> std::ops::ControlFlow<()>;

    /// Asked between the steps of one long objective evaluation (the
    /// iterative exact GP's conjugate-gradient iterations): `true` stops the
    /// fit there, as `ControlFlow::Break` from [`FitProgress::iteration`]
    /// does. Never asked to stop by default.
    fn stop_requested(&self) -> bool {
        false
    }
}

/// A regressor of odometry residuals.
///
/// `fit` learns from a batch; `predict` returns mean and variance per output;
/// incremental learners also implement `update` (one sample at a time, the
/// previous posterior acting as prior) and return `true` from
/// `supports_online_update`.
///
/// ```
/// use gpodo_traits::{Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix};
///
/// /// Predicts the training mean of each output with the training variance.
/// #[derive(Default)]
/// struct MeanOnly { mean: Vec<f64>, var: Vec<f64> }
///
/// impl ResidualRegressor for MeanOnly {
///     fn name(&self) -> &str { "mean_only" }
///     fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
///         let n = data.len() as f64;
///         let o = data.targets.ncols();
///         self.mean = (0..o).map(|j| data.targets.column(j).iter().sum::<f64>() / n).collect();
///         self.var = (0..o).map(|j| data.targets.column(j).iter()
///             .map(|y| (y - self.mean[j]).powi(2)).sum::<f64>() / n).collect();
///         Ok(FitReport { n_samples: data.len(), ..Default::default() })
///     }
///     fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
///         let rows = vec![self.mean.clone(); inputs.nrows()];
///         let vars = vec![self.var.clone(); inputs.nrows()];
///         Ok(Predictions {
///             mean: SampleMatrix::from_rows(self.mean.len(), &rows)?,
///             variance: SampleMatrix::from_rows(self.var.len(), &vars)?,
///         })
///     }
/// }
///
/// let x = SampleMatrix::from_rows(1, &[[0.0], [1.0]]).unwrap();
/// let y = SampleMatrix::from_rows(1, &[[1.0], [3.0]]).unwrap();
/// let data = ResidualDataset::new(x.clone(), y, vec!["x".into()], vec!["y".into()]).unwrap();
/// let mut model: Box<dyn ResidualRegressor> = Box::new(MeanOnly::default());
/// model.fit(&data).unwrap();
/// let p = model.predict(&x).unwrap();
/// assert_eq!(p.mean.get(0, 0), 2.0);
/// assert_eq!(p.variance.get(1, 0), 1.0);
/// assert!(model.update(&[0.0], &[1.0]).is_err());
/// ```
pub trait ResidualRegressor: Send + Sync {
    /// A short name for reports (e.g. `"exact_gp[rbf]"`).
    fn name(&self) -> &str;

    /// Learns from a batch, replacing what was learned before.
    ///
    /// # Errors
    /// Implementation-specific: empty data, non-finite values, a failed
    /// factorisation.
    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error>;

    /// Predicts mean and variance for each row of `inputs`.
    ///
    /// # Errors
    /// [`Error::NotFitted`] before `fit`, [`Error::DimensionMismatch`] when
    /// the inputs have the wrong number of columns.
    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error>;

    /// Whether [`ResidualRegressor::update`] learns online.
    fn supports_online_update(&self) -> bool {
        false
    }

    /// Where to report the optimiser's progress during `fit` (models
    /// without an iterative fit ignore it).
    fn set_progress(&mut self, progress: Option<std::sync::Arc<dyn FitProgress>>) {
        let _ = progress;
    }

    /// Learns from one more sample (online learning).
    ///
    /// # Errors
    /// [`Error::OnlineUpdateUnsupported`] for batch-only models.
    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        let _ = (inputs, targets);
        Err(Error::OnlineUpdateUnsupported {
            model: self.name().to_string(),
        })
    }

    /// Learns from a batch of new samples as one batch, where the caller
    /// decides where a batch ends (Table II's online schemes end one every
    /// so many seconds of VO targets). Learners that learn in batches (the
    /// streaming sparse GP) learn these rows, with any that `update` left
    /// waiting, in one step, whatever their number; the others learn them
    /// one [`ResidualRegressor::update`] at a time, which is the default.
    ///
    /// # Errors
    /// As [`ResidualRegressor::update`]. The default learns the rows before
    /// the failing one; a batch learner may check every row first and
    /// learn none of the batch when one is bad.
    fn update_batch(&mut self, data: &ResidualDataset) -> Result<(), Error> {
        for i in 0..data.len() {
            self.update(data.inputs.row(i), data.targets.row(i))?;
        }
        Ok(())
    }
}
