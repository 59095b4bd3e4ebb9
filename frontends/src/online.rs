//! Online learning of the residual from visual odometry (the paper's
//! future work, §VI): the regressor is not trained on ground truth; each
//! VO target the front end measures (the VO displacement over an interval
//! minus the parametric odometry's, per second) is learned as it arrives,
//! and the gating policy reads the current model. While the model knows
//! nothing its predictive variance is large and frames are requested
//! often; as it learns, less.

use gpodo_traits::{Error, ResidualDataset, ResidualRegressor, SampleMatrix};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::prediction::{ResidualPrediction, ResidualSource};
use crate::traverse::TraverseWindow;

/// How an online source learns.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case", deny_unknown_fields)]
pub enum OnlineMode {
    /// One `update` per target (incremental learners such as ILGR).
    Update,
    /// Refit from scratch on all targets so far every `every` targets
    /// (batch learners such as the sparse GP).
    Refit {
        /// Targets between refits (default 25).
        #[serde(default = "default_refit_every")]
        every: usize,
        /// Fewest targets for a first fit (default 20).
        #[serde(default = "default_min_targets")]
        min_targets: usize,
    },
}

fn default_refit_every() -> usize {
    25
}

fn default_min_targets() -> usize {
    20
}

/// A regressor learning from VO targets, behind [`ResidualSource`].
pub struct OnlineLearner {
    name: String,
    model: Box<dyn ResidualRegressor>,
    mode: OnlineMode,
    prior_variance: f64,
    inputs: Vec<f64>,
    targets: Vec<f64>,
    n_inputs: Option<usize>,
    since_refit: usize,
    fitted: bool,
    /// `(time, targets so far)` after each target.
    history: Vec<(f64, usize)>,
    /// Whether the window inputs are z-scored already.
    inputs_standardized: bool,
}

impl OnlineLearner {
    /// Learns with `model` (fresh; it sees only VO targets) in `mode`;
    /// before it can predict, the prediction is zero mean with variance
    /// `prior_variance` per axis.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] when `mode` is `update` and the model
    /// cannot learn online, or a refit count is zero.
    pub fn new(
        name: impl Into<String>,
        model: Box<dyn ResidualRegressor>,
        mode: OnlineMode,
        prior_variance: f64,
    ) -> Result<Self, FrontendError> {
        match mode {
            OnlineMode::Update if !model.supports_online_update() => {
                return Err(FrontendError::InvalidConfig {
                    field: "online.mode".into(),
                    expected: format!(
                        "`refit` for `{}`, which cannot learn one sample at a time",
                        model.name()
                    ),
                });
            }
            OnlineMode::Refit { every, min_targets } if every == 0 || min_targets == 0 => {
                return Err(FrontendError::InvalidConfig {
                    field: "online.every".into(),
                    expected: "at least 1 target between refits and for the first fit".into(),
                });
            }
            _ => {}
        }
        Ok(Self {
            name: name.into(),
            model,
            mode,
            prior_variance,
            inputs: Vec::new(),
            targets: Vec::new(),
            n_inputs: None,
            since_refit: 0,
            fitted: false,
            history: Vec::new(),
            inputs_standardized: false,
        })
    }

    /// Tells the learner that the window inputs it will see are z-scored
    /// already ([`Traverse::inputs_standardized`](crate::traverse::Traverse::inputs_standardized)),
    /// so that the rows it refits on say so.
    #[must_use]
    pub fn with_standardized_inputs(mut self, standardized: bool) -> Self {
        self.inputs_standardized = standardized;
        self
    }

    /// Targets learned so far.
    pub fn targets_seen(&self) -> usize {
        self.targets.len() / 3
    }

    /// `(time, targets so far)` after each target.
    pub fn history(&self) -> &[(f64, usize)] {
        &self.history
    }

    fn refit(&mut self) -> Result<(), FrontendError> {
        let (n, d) = (self.targets.len() / 3, self.n_inputs.unwrap_or(0));
        let data = ResidualDataset::new(
            SampleMatrix::from_row_major(n, d, self.inputs.clone())?,
            SampleMatrix::from_row_major(n, 3, self.targets.clone())?,
            (0..d).map(|i| format!("x{i}")).collect(),
            ["res_vx", "res_vy", "res_vz"].map(String::from).to_vec(),
        )?
        .with_standardized_inputs(self.inputs_standardized);
        self.model.fit(&data)?;
        self.fitted = true;
        self.since_refit = 0;
        Ok(())
    }
}

impl ResidualSource for OnlineLearner {
    fn name(&self) -> &str {
        &self.name
    }

    fn on_window(
        &mut self,
        _index: usize,
        window: &TraverseWindow,
    ) -> Result<ResidualPrediction, FrontendError> {
        let uninformed = ResidualPrediction::uninformed(self.prior_variance);
        if !self.fitted {
            return Ok(uninformed);
        }
        let x = SampleMatrix::from_row_major(1, window.inputs.len(), window.inputs.clone())?;
        match self.model.predict(&x) {
            Ok(p) => Ok(ResidualPrediction {
                mean: Vector3::from_iterator(p.mean.row(0).iter().copied()),
                variance: Vector3::from_iterator(p.variance.row(0).iter().copied()),
                absolute: None,
            }),
            Err(Error::NotFitted { .. }) => Ok(uninformed),
            Err(e) => Err(e.into()),
        }
    }

    fn learns_online(&self) -> bool {
        true
    }

    fn on_target(
        &mut self,
        inputs: &[f64],
        target: &Vector3<f64>,
        time_secs: f64,
    ) -> Result<(), FrontendError> {
        if *self.n_inputs.get_or_insert(inputs.len()) != inputs.len() {
            return Err(Error::DimensionMismatch {
                what: "online target inputs".into(),
                expected: self.n_inputs.unwrap_or(0),
                found: inputs.len(),
            }
            .into());
        }
        self.inputs.extend_from_slice(inputs);
        self.targets.extend(target.iter());
        match self.mode {
            OnlineMode::Update => {
                self.model.update(inputs, target.as_slice())?;
                self.fitted = true;
            }
            OnlineMode::Refit { every, min_targets } => {
                self.since_refit += 1;
                if self.targets_seen() >= min_targets && (!self.fitted || self.since_refit >= every)
                {
                    self.refit()?;
                }
            }
        }
        self.history.push((time_secs, self.targets_seen()));
        Ok(())
    }
}
