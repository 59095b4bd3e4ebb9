//! [`Ilgr`]: incremental local Gaussian regression behind
//! [`ResidualRegressor`]. `fit` resets and runs `passes` online passes over
//! the batch; `update` is one online step and works without a prior `fit`;
//! predictions are mapped back to target units (mean × scale + offset,
//! variance × scale²).

use std::time::Instant;

use gpodo_traits::MIN_STD;
use gpodo_traits::{
    Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
};
use nalgebra::DVector;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

use super::params::IlgrParams;
use super::state::{IlgrState, Workspace};
use crate::RegressorError;

/// Incremental local Gaussian regression (Meier, Hennig & Schaal, 2014).
#[derive(Debug, Clone)]
pub struct Ilgr {
    params: IlgrParams,
    state: Option<IlgrState>,
    workspace: Workspace,
    standardised: Vec<f64>,
}

fn non_finite(what: &str, values: &[f64]) -> Option<Error> {
    values
        .iter()
        .position(|v| !v.is_finite())
        .map(|j| Error::InvalidInput(format!("{what}: non-finite value in column {j}")))
}

impl Ilgr {
    /// An ILGR with checked settings and no local models.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the bad field.
    pub fn new(params: IlgrParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            params,
            state: None,
            workspace: Workspace::default(),
            standardised: Vec::new(),
        })
    }

    /// Rebuilds an ILGR from a saved state, to predict or continue learning.
    ///
    /// # Errors
    /// As [`IlgrParams::check`], or [`RegressorError::InvalidData`] when the
    /// state's shapes disagree or it holds non-finite values.
    pub fn from_state(mut state: IlgrState) -> Result<Self, RegressorError> {
        state.params.check()?;
        let (d, o) = (state.n_inputs, state.n_outputs());
        let k = d + 1;
        let consistent = d > 0
            && o > 0
            && state.target_offset.len() == o
            && state.target_scale.iter().all(|s| s.is_finite() && *s > 0.0)
            && state.models.iter().all(|m| {
                let w = &m.posterior;
                m.centre.len() == d
                    && m.lengthscale.len() == d
                    && m.lengthscale.iter().all(|l| l.is_finite() && *l > 0.0)
                    && m.s_phi_phi.shape() == (k, k)
                    && w.mean.shape() == (k, o)
                    && w.cov.shape() == (k, k)
                    && w.s_phi_f.shape() == (k, o)
                    && w.ard.len() == k
                    && w.mean.iter().chain(w.cov.iter()).all(|v| v.is_finite())
            });
        if !consistent {
            return Err(RegressorError::InvalidData {
                detail: "saved ILGR state: shapes disagree or values are not finite".into(),
            });
        }
        for model in &mut state.models {
            model.sync_lengthscales();
        }
        Ok(Self {
            params: state.params.clone(),
            state: Some(state),
            workspace: Workspace::default(),
            standardised: Vec::new(),
        })
    }

    /// The settings.
    pub fn params(&self) -> &IlgrParams {
        &self.params
    }

    /// The learned state (None before any data), serialisable.
    pub fn state(&self) -> Option<&IlgrState> {
        self.state.as_ref()
    }

    /// Number of local models.
    pub fn n_local_models(&self) -> usize {
        self.state.as_ref().map_or(0, |s| s.models.len())
    }

    /// Local models created so far (since the last `fit` or `reset`).
    pub fn models_created(&self) -> u64 {
        self.state.as_ref().map_or(0, |s| s.models_created)
    }

    /// Local models pruned so far (since the last `fit` or `reset`).
    pub fn models_pruned(&self) -> u64 {
        self.state.as_ref().map_or(0, |s| s.models_pruned)
    }

    /// Forgets everything learned (the next `update` starts from scratch).
    pub fn reset(&mut self) {
        self.state = None;
    }

    /// The activation `η_m(x)` of every local model at `x`, without cutoff.
    ///
    /// # Errors
    /// As [`Ilgr::predict_row`] for the input.
    pub fn activations(&self, x: &[f64]) -> Result<Vec<f64>, Error> {
        let state = self.checked_state(x)?;
        Ok(state.models.iter().map(|m| m.activation(x)).collect())
    }

    fn checked_state(&self, x: &[f64]) -> Result<&IlgrState, Error> {
        let Some(state) = &self.state else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        if x.len() != state.n_inputs {
            return Err(Error::DimensionMismatch {
                what: "ILGR input columns".into(),
                expected: state.n_inputs,
                found: x.len(),
            });
        }
        if let Some(e) = non_finite("ILGR input", x) {
            return Err(e);
        }
        Ok(state)
    }

    /// Predictive mean and variance (target units) at one input, written
    /// into `mean` and `variance` (one entry per output). Costs
    /// `O(M d + A K²)` and one small allocation; with [`ResidualRegressor::update`]
    /// it is what a per-sample timing loop calls.
    ///
    /// # Errors
    /// [`Error::NotFitted`] before any data; [`Error::DimensionMismatch`] for
    /// a wrong input width or output buffers of the wrong length;
    /// [`Error::InvalidInput`] for a non-finite input.
    pub fn predict_row(
        &self,
        x: &[f64],
        mean: &mut [f64],
        variance: &mut [f64],
    ) -> Result<(), Error> {
        let state = self.checked_state(x)?;
        let o = state.n_outputs();
        for (what, found) in [
            ("mean buffer", mean.len()),
            ("variance buffer", variance.len()),
        ] {
            if found != o {
                return Err(Error::DimensionMismatch {
                    what: format!("ILGR {what}"),
                    expected: o,
                    found,
                });
            }
        }
        let mut phi = DVector::zeros(state.n_inputs + 1);
        let mut active = Vec::new();
        Self::predict_into(state, x, &mut phi, &mut active, mean, variance);
        Ok(())
    }

    fn predict_into(
        state: &IlgrState,
        x: &[f64],
        phi: &mut DVector<f64>,
        active: &mut Vec<(usize, f64)>,
        mean: &mut [f64],
        variance: &mut [f64],
    ) {
        let v = state.predict_standardised(x, phi, active, mean);
        for out in 0..mean.len() {
            let scale = state.target_scale[out];
            mean[out] = state.target_offset[out] + scale * mean[out];
            variance[out] = v * scale * scale;
        }
    }

    /// One online step with already checked values.
    fn learn(&mut self, x: &[f64], y: &[f64]) -> Result<(), Error> {
        let Some(state) = &mut self.state else {
            return Err(Error::NotFitted {
                model: "ilgr".into(),
            });
        };
        self.standardised.clear();
        self.standardised.extend(
            y.iter()
                .zip(state.target_offset.iter().zip(&state.target_scale))
                .map(|(v, (offset, scale))| (v - offset) / scale),
        );
        state.step(x, &self.standardised, &mut self.workspace);
        Ok(())
    }

    fn target_scaling(&self, targets: &SampleMatrix) -> (Vec<f64>, Vec<f64>) {
        let o = targets.ncols();
        if !self.params.standardize_targets {
            return (vec![0.0; o], vec![self.params.target_scale; o]);
        }
        let n = targets.nrows() as f64;
        (0..o)
            .map(|j| {
                let column = targets.column(j);
                let mean = column.iter().sum::<f64>() / n;
                let std = (column.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
                (
                    mean,
                    if std <= MIN_STD {
                        self.params.target_scale
                    } else {
                        std
                    },
                )
            })
            .unzip()
    }

    fn fit_impl(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        let start = Instant::now();
        let (n, d, o) = (data.len(), data.inputs.ncols(), data.targets.ncols());
        if n == 0 || d == 0 || o == 0 {
            return Err(RegressorError::InvalidData {
                detail: format!(
                    "need samples, inputs and outputs; got {n} × {d} inputs, {o} outputs"
                ),
            }
            .into());
        }
        for (what, m) in [("inputs", &data.inputs), ("targets", &data.targets)] {
            for (i, row) in m.rows().enumerate() {
                if let Some(j) = row.iter().position(|v| !v.is_finite()) {
                    return Err(RegressorError::InvalidData {
                        detail: format!("{what}: non-finite value at row {i}, column {j}"),
                    }
                    .into());
                }
            }
        }
        let (offset, scale) = self.target_scaling(&data.targets);
        self.state = Some(IlgrState::new(self.params.clone(), d, offset, scale));
        let mut order: Vec<usize> = (0..n).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(self.params.seed);
        for _ in 0..self.params.passes {
            if self.params.shuffle {
                order.shuffle(&mut rng);
            }
            for &i in &order {
                self.learn(data.inputs.row(i), data.targets.row(i))?;
            }
        }
        Ok(self.report(data, start))
    }

    fn report(&self, data: &ResidualDataset, start: Instant) -> FitReport {
        let mut report = FitReport {
            n_samples: data.len(),
            ..Default::default()
        };
        if let Some(state) = &self.state {
            let p = &state.params;
            report
                .parameters
                .push(("local_models".into(), state.models.len() as f64));
            report
                .parameters
                .push(("models_created".into(), state.models_created as f64));
            report
                .parameters
                .push(("models_pruned".into(), state.models_pruned as f64));
            let log_lengthscales: Vec<f64> = state
                .models
                .iter()
                .flat_map(|m| m.lengthscale.iter().map(|l| l.ln()))
                .collect();
            if !log_lengthscales.is_empty() {
                let mean = log_lengthscales.iter().sum::<f64>() / log_lengthscales.len() as f64;
                report
                    .parameters
                    .push(("lengthscale_geometric_mean".into(), mean.exp()));
            }
            let output_noise = state.output_noise.variance(&p.output_noise_precision_prior);
            for (out, scale) in state.target_scale.iter().enumerate() {
                let name = data.target_names.get(out).cloned().unwrap_or_default();
                report.parameters.push((
                    format!("{name}.output_noise_variance"),
                    output_noise * scale * scale,
                ));
            }
        }
        report.duration_secs = start.elapsed().as_secs_f64();
        report
    }
}

impl ResidualRegressor for Ilgr {
    fn name(&self) -> &str {
        "ilgr"
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        self.fit_impl(data)
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let Some(state) = &self.state else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        if inputs.ncols() != state.n_inputs {
            return Err(Error::DimensionMismatch {
                what: "ILGR input columns".into(),
                expected: state.n_inputs,
                found: inputs.ncols(),
            });
        }
        let (n, o) = (inputs.nrows(), state.n_outputs());
        let mut mean = SampleMatrix::zeros(n, o);
        let mut variance = SampleMatrix::zeros(n, o);
        let mut phi = DVector::zeros(state.n_inputs + 1);
        let mut active = Vec::new();
        for (i, x) in inputs.rows().enumerate() {
            if let Some(j) = x.iter().position(|v| !v.is_finite()) {
                return Err(Error::InvalidInput(format!(
                    "ILGR input: non-finite value at row {i}, column {j}"
                )));
            }
            Self::predict_into(
                state,
                x,
                &mut phi,
                &mut active,
                mean.row_mut(i),
                variance.row_mut(i),
            );
        }
        Ok(Predictions { mean, variance })
    }

    fn supports_online_update(&self) -> bool {
        true
    }

    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        if inputs.is_empty() || targets.is_empty() {
            return Err(Error::InvalidInput(format!(
                "ILGR update needs inputs and targets; got {} inputs, {} targets",
                inputs.len(),
                targets.len()
            )));
        }
        if let Some(state) = &self.state {
            for (what, expected, found) in [
                ("ILGR input columns", state.n_inputs, inputs.len()),
                ("ILGR target columns", state.n_outputs(), targets.len()),
            ] {
                if expected != found {
                    return Err(Error::DimensionMismatch {
                        what: what.into(),
                        expected,
                        found,
                    });
                }
            }
        }
        if let Some(e) = non_finite("ILGR update input", inputs)
            .or_else(|| non_finite("ILGR update target", targets))
        {
            return Err(e);
        }
        if self.state.is_none() {
            let o = targets.len();
            self.state = Some(IlgrState::new(
                self.params.clone(),
                inputs.len(),
                vec![0.0; o],
                vec![self.params.target_scale; o],
            ));
        }
        self.learn(inputs, targets)
    }
}
