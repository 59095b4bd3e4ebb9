//! The streaming sparse GP as a regressor (`kind: streaming_sparse_gp`):
//! rows arrive one at a time and are learned in batches, each batch's
//! posterior over its inducing outputs the prior of the next, no row ever
//! seen twice.
//!
//! - **First batch** (`warmup_rows` rows): z-scoring from its statistics,
//!   inducing inputs placed by k-means, hyperparameters and inducing inputs
//!   learned with the sparse GP's `hyperopt` recipe on its bound (the batch
//!   VFE bound, since nothing came before).
//! - **Each later batch** (`batch_rows` rows): the inducing inputs are kept
//!   and added to (every old one while there are fewer than
//!   `inducing.count`; then a seeded random `kept_inducing` share of the
//!   old ones and the rest drawn from the batch's inputs, as the authors'
//!   experiments do); L-BFGS climbs the streaming bound over the
//!   hyperparameters and those inducing inputs for `batch_iters`
//!   iterations from where the previous batch ended; the optimal `q(b)`
//!   there becomes the new summary.

use std::time::Instant;

use gpodo_traits::{
    Error, FitProgress, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
    Standardizer,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::bound::streaming_fit;
use super::inducing::keep_and_add;
use super::objective::{BatchObjective, flat};
use super::params::StreamingSparseGpParams;
use super::state::{StreamingSparseGpState, saved_to_summary, summary_to_saved};
use crate::RegressorError;
use crate::dense::{from_faer, to_faer};
use crate::hyperopt::{
    Coordinates, HyperProblem, LogBounds, Objective, ProgressSink, learn, maximize, starts,
};
use crate::scaling::{ScaledTraining, check_finite};
use crate::sparse_gp::SparsePosterior;
use crate::sparse_gp::inducing::place_inducing;
use crate::stream_rows::{rows_dataset, running_moments};

/// What one later batch cost (s): the hyperparameter step (L-BFGS on
/// the bound) and the posterior update (placing its inducing inputs and
/// the optimal `q(b)` at the hyperparameters it ended with).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchTiming {
    /// The hyperparameter step.
    pub hyperparameter_secs: f64,
    /// The posterior update.
    pub update_secs: f64,
}

/// The streaming sparse GP regressor.
#[derive(Debug, Clone)]
pub struct StreamingSparseGp {
    params: StreamingSparseGpParams,
    learned: Option<(StreamingSparseGpState, SparsePosterior)>,
    /// Rows of a stream kept until the first batch is complete.
    buffer: Vec<(Vec<f64>, Vec<f64>)>,
    progress: ProgressSink,
    timings: Vec<BatchTiming>,
}

impl StreamingSparseGp {
    /// A model with checked settings.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bad field.
    pub fn new(params: StreamingSparseGpParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            params,
            learned: None,
            buffer: Vec::new(),
            progress: ProgressSink::default(),
            timings: Vec::new(),
        })
    }

    /// The learned state (None before the first batch).
    pub fn state(&self) -> Option<&StreamingSparseGpState> {
        self.learned.as_ref().map(|(s, _)| s)
    }

    /// What each later batch learned since this model was built cost, in
    /// order (for latency measurements; not saved).
    pub fn batch_timings(&self) -> &[BatchTiming] {
        &self.timings
    }

    /// The posterior predictions come from (None before the first batch).
    pub fn posterior(&self) -> Option<&SparsePosterior> {
        self.learned.as_ref().map(|(_, p)| p)
    }

    /// Rebuilds a model from its saved state; it predicts and goes on
    /// learning as the model that was saved would have.
    ///
    /// # Errors
    /// [`RegressorError::InvalidData`] when the state is inconsistent.
    pub fn from_state(state: StreamingSparseGpState) -> Result<Self, RegressorError> {
        state.params.check()?;
        let s = &state.summary;
        for (what, m) in [
            ("saved inducing inputs", &s.inducing),
            ("saved prior covariance", &s.prior_covariance),
            ("saved data precision", &s.data_precision),
            ("saved natural mean", &s.natural_mean),
            ("saved weights", &state.weights),
            ("saved variance matrix", &state.variance_matrix),
        ] {
            check_finite(what, m)?;
        }
        let m = s.inducing.nrows();
        let consistent = [
            &s.prior_covariance,
            &s.data_precision,
            &state.variance_matrix,
        ]
        .iter()
        .all(|a| a.nrows() == m && a.ncols() == m)
            && s.natural_mean.nrows() == m
            && s.natural_mean.ncols() == state.target_names.len()
            && state.weights.nrows() == m
            && state.weights.ncols() == state.target_names.len()
            && s.inducing.ncols() == state.input_names.len();
        if !consistent {
            return Err(RegressorError::InvalidData {
                detail: "saved streaming sparse GP state: its summary's shapes disagree with each other or with its columns".into(),
            });
        }
        let posterior = SparsePosterior {
            kernel: state.kernel.clone(),
            noise_variance: state.noise_variance,
            inducing: to_faer(&s.inducing),
            weights: to_faer(&state.weights),
            variance_matrix: to_faer(&state.variance_matrix),
            objective: state.objective,
            extra_jitter: 0.0,
        };
        Ok(Self {
            params: state.params.clone(),
            learned: Some((state, posterior)),
            buffer: Vec::new(),
            progress: ProgressSink::default(),
            timings: Vec::new(),
        })
    }

    /// The first batch: scaling, placement and the full recipe.
    fn first_batch(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        let start = Instant::now();
        let p = &self.params;
        let scaled = ScaledTraining::new(data, p.standardize)?;
        let (x, y) = (to_faer(&scaled.x), to_faer(&scaled.y));
        let z0 = place_inducing(x.as_ref(), &p.inducing, p.seed);
        let template = p.kernel.build(x.ncols(), &p.init);
        let objective = BatchObjective {
            template: &template,
            x: x.as_ref(),
            y: y.as_ref(),
            inducing: &z0,
            learn_inducing: !p.inducing.fixed,
            old: None,
            jitter: p.jitter,
        };
        let z_coords = if objective.learn_inducing {
            flat(z0.as_ref())
        } else {
            Vec::new()
        };
        let bases = starts::kernel_bases(&p.kernel, &p.init, objective.x, p.noise_variance)
            .into_iter()
            .map(|(label, mut c)| {
                c.extend_from_slice(&z_coords);
                (label, c)
            })
            .collect();
        let score = |c: &[f64]| objective.evaluate(c).map(|(v, _)| v);
        let problem = HyperProblem {
            objective: &objective,
            score: &score,
            space: objective.space(&p.hyperopt.bounds),
            bases,
            value_scale: 1.0 / (y.nrows() * y.ncols()) as f64,
        };
        let (out, starts) = learn(&problem, &p.hyperopt, p.seed, &self.progress)?;
        let (kernel, noise, z) = objective.unpack(&out.coords);
        let fit = streaming_fit(objective.problem(&kernel, noise, &z))?;
        let state = StreamingSparseGpState {
            params: self.params.clone(),
            input_names: data.input_names.clone(),
            target_names: data.target_names.clone(),
            input_scaler: scaled.input_scaler,
            output_scaler: scaled.output_scaler,
            kernel,
            noise_variance: noise,
            summary: summary_to_saved(&fit.summary),
            weights: from_faer(fit.posterior.weights.as_ref()),
            variance_matrix: from_faer(fit.posterior.variance_matrix.as_ref()),
            objective: fit.value,
            batches: 1,
            rows_seen: data.len(),
            pending: Vec::new(),
        };
        let report = FitReport {
            n_samples: data.len(),
            duration_secs: start.elapsed().as_secs_f64(),
            objective: Some(fit.value),
            evaluations: Some(out.evaluations),
            iterations: Some(out.iterations),
            starts,
            ..FitReport::default()
        };
        self.learned = Some((state, fit.posterior));
        Ok(report)
    }

    /// Learns a later batch of raw rows from the summary.
    fn next_batch(&mut self, rows: &[(Vec<f64>, Vec<f64>)]) -> Result<(), RegressorError> {
        let Some((state, _)) = &self.learned else {
            return Err(RegressorError::InvalidData {
                detail: "streaming_sparse_gp: a later batch before the first".into(),
            });
        };
        let p = &self.params;
        let placed = Instant::now();
        let data = rows_dataset(rows)?;
        let scale = |m: &SampleMatrix, s: &Option<Standardizer>| match s {
            Some(s) => s.transform(m).map(|m| to_faer(&m)),
            None => Ok(to_faer(m)),
        };
        let x = scale(&data.inputs, &state.input_scaler)?;
        let y = scale(&data.targets, &state.output_scaler)?;
        let old = saved_to_summary(&state.summary);
        // A stream of its own per batch, so that a saved model goes on as
        // the one that was saved.
        let mut rng = ChaCha8Rng::seed_from_u64(
            p.seed ^ (state.batches as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let zb0 = keep_and_add(
            &state.kernel,
            old.inducing.as_ref(),
            x.as_ref(),
            p.inducing.count,
            p.kept_inducing,
            &mut rng,
        );
        let objective = BatchObjective {
            template: &state.kernel,
            x: x.as_ref(),
            y: y.as_ref(),
            inducing: &zb0,
            learn_inducing: !p.inducing.fixed,
            old: Some(&old),
            jitter: p.jitter,
        };
        let start = objective.pack(&state.kernel, state.noise_variance);
        let placing_secs = placed.elapsed().as_secs_f64();
        let stepped = Instant::now();
        let (kernel, noise, z) = if p.batch_iters == 0 {
            objective.unpack(&start)
        } else {
            let mut space = objective.space(&p.hyperopt.bounds);
            // A trust region around the previous batch's hyperparameters.
            let hyper = state.kernel.n_params() + 1;
            for (b, c) in space.bounds.iter_mut().zip(&start).take(hyper) {
                let (lo, hi) = (
                    b.lower().max(c - p.batch_log_step),
                    b.upper().min(c + p.batch_log_step),
                );
                *b = LogBounds::new([lo.exp(), hi.exp()]);
            }
            let coords = Coordinates {
                start,
                bounds: space.bounds,
                perturb: space.perturb,
            };
            let mut settings = p.hyperopt.settings(p.seed);
            settings.max_iters = p.batch_iters;
            settings.restarts = 0;
            match maximize(
                &objective,
                &coords,
                1.0 / (y.nrows() * y.ncols()) as f64,
                &settings,
                self.progress.0.as_ref(),
            ) {
                Ok(out) => objective.unpack(&out.coords),
                Err(RegressorError::Stopped) => return Err(RegressorError::Stopped),
                Err(e) => {
                    tracing::warn!(
                        batch = state.batches + 1,
                        "streaming_sparse_gp: the batch's hyperparameter step failed ({e}); \
                         the previous hyperparameters are kept"
                    );
                    objective.unpack(&coords.start)
                }
            }
        };
        let hyperparameter_secs = stepped.elapsed().as_secs_f64();
        let updated = Instant::now();
        // Where the step ended cannot be factorised (it went too far): the
        // batch is learned at the previous hyperparameters instead.
        let (kernel, noise, fit) = match streaming_fit(objective.problem(&kernel, noise, &z)) {
            Ok(fit) => (kernel, noise, fit),
            Err(e) => {
                tracing::warn!(
                    batch = state.batches + 1,
                    "streaming_sparse_gp: the batch's posterior failed where its hyperparameter \
                     step ended ({e}); it is learned at the previous hyperparameters"
                );
                let (kernel, noise, z) =
                    objective.unpack(&objective.pack(&state.kernel, state.noise_variance));
                let fit = streaming_fit(objective.problem(&kernel, noise, &z))?;
                (kernel, noise, fit)
            }
        };
        self.timings.push(BatchTiming {
            hyperparameter_secs,
            update_secs: placing_secs + updated.elapsed().as_secs_f64(),
        });
        let Some((state, posterior)) = &mut self.learned else {
            return Ok(());
        };
        state.kernel = kernel;
        state.noise_variance = noise;
        state.summary = summary_to_saved(&fit.summary);
        state.weights = from_faer(fit.posterior.weights.as_ref());
        state.variance_matrix = from_faer(fit.posterior.variance_matrix.as_ref());
        state.objective = fit.value;
        state.batches += 1;
        state.rows_seen += rows.len();
        *posterior = fit.posterior;
        Ok(())
    }

    fn fit_impl(&mut self, data: &ResidualDataset) -> Result<FitReport, RegressorError> {
        let start = Instant::now();
        self.learned = None;
        self.buffer.clear();
        let n = data.len();
        if n < 2 {
            return Err(RegressorError::InvalidData {
                detail: "streaming_sparse_gp needs at least 2 rows".into(),
            });
        }
        let w = self.params.warmup_rows.min(n);
        let mut report = self.first_batch(&data.select(&(0..w).collect::<Vec<_>>()))?;
        let rows: Vec<(Vec<f64>, Vec<f64>)> = (w..n)
            .map(|i| (data.inputs.row(i).to_vec(), data.targets.row(i).to_vec()))
            .collect();
        for batch in rows.chunks(self.params.batch_rows) {
            if self.progress.stop_requested() {
                return Err(RegressorError::Stopped);
            }
            self.next_batch(batch)?;
        }
        if let Some((state, posterior)) = &self.learned {
            report.objective = Some(state.objective);
            report.parameters = state
                .kernel
                .param_names(&data.input_names)
                .into_iter()
                .zip(state.kernel.log_params().into_iter().map(f64::exp))
                .chain([
                    ("noise_variance".to_string(), state.noise_variance),
                    (
                        "inducing_points".to_string(),
                        posterior.inducing.nrows() as f64,
                    ),
                    ("batches".to_string(), state.batches as f64),
                ])
                .collect();
        }
        report.n_samples = n;
        report.duration_secs = start.elapsed().as_secs_f64();
        Ok(report)
    }

    /// A stream's row: kept until its batch is complete, then learned.
    fn learn_row(&mut self, x: &[f64], y: &[f64]) -> Result<(), Error> {
        self.check_row(x, y)?;
        match &mut self.learned {
            None => {
                self.buffer.push((x.to_vec(), y.to_vec()));
                if self.buffer.len() >= self.params.warmup_rows {
                    let rows = std::mem::take(&mut self.buffer);
                    self.first_batch(&rows_dataset(&rows)?)?;
                }
            }
            Some((state, _)) => {
                state.pending.push((x.to_vec(), y.to_vec()));
                if state.pending.len() >= self.params.batch_rows {
                    let rows = std::mem::take(&mut state.pending);
                    self.next_batch(&rows)?;
                }
            }
        }
        Ok(())
    }

    /// A batch the caller ended: learned now with the rows waiting, as the
    /// first batch (from at least 2 rows; fewer wait) or as the next one,
    /// whatever `warmup_rows` and `batch_rows` say.
    fn learn_batch(&mut self, data: &ResidualDataset) -> Result<(), Error> {
        let mut rows = Vec::with_capacity(data.len());
        for i in 0..data.len() {
            let (x, y) = (data.inputs.row(i), data.targets.row(i));
            self.check_row(x, y)?;
            rows.push((x.to_vec(), y.to_vec()));
        }
        match &mut self.learned {
            None => {
                self.buffer.extend(rows);
                if self.buffer.len() >= 2 {
                    let rows = std::mem::take(&mut self.buffer);
                    self.first_batch(&rows_dataset(&rows)?)?;
                }
            }
            Some((state, _)) => {
                let mut batch = std::mem::take(&mut state.pending);
                batch.extend(rows);
                if !batch.is_empty() {
                    self.next_batch(&batch)?;
                }
            }
        }
        Ok(())
    }

    /// Checks a stream's row against the widths seen so far.
    fn check_row(&self, x: &[f64], y: &[f64]) -> Result<(), Error> {
        let width = match &self.learned {
            Some((s, _)) => Some((s.input_names.len(), s.target_names.len())),
            None => self.buffer.first().map(|(x0, y0)| (x0.len(), y0.len())),
        };
        if let Some((d, p)) = width
            && (x.len() != d || y.len() != p)
        {
            return Err(Error::DimensionMismatch {
                what: "streaming_sparse_gp inputs and targets".into(),
                expected: d + p,
                found: x.len() + y.len(),
            });
        }
        if x.iter().chain(y).any(|v| !v.is_finite()) {
            return Err(Error::InvalidInput(
                "streaming_sparse_gp: a non-finite input or target".into(),
            ));
        }
        Ok(())
    }

    /// Before the first batch: the kept rows' mean and variance per output
    /// (an error before any row).
    fn predict_before_first_batch(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        running_moments(self.name(), &self.buffer, inputs)
    }
}

impl ResidualRegressor for StreamingSparseGp {
    fn name(&self) -> &str {
        "streaming_sparse_gp"
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        self.fit_impl(data).map_err(Error::from)
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let Some((state, posterior)) = &self.learned else {
            return self.predict_before_first_batch(inputs);
        };
        let full = posterior.predict_scaled(
            self.name(),
            inputs,
            state.input_names.len(),
            state.input_scaler.as_ref(),
            state.output_scaler.as_ref(),
        )?;
        Ok(Predictions {
            mean: full.mean,
            variance: full.variance,
        })
    }

    fn set_progress(&mut self, progress: Option<std::sync::Arc<dyn FitProgress>>) {
        self.progress = ProgressSink(progress);
    }

    fn supports_online_update(&self) -> bool {
        true
    }

    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        self.learn_row(inputs, targets)
    }

    fn update_batch(&mut self, data: &ResidualDataset) -> Result<(), Error> {
        self.learn_batch(data)
    }
}
