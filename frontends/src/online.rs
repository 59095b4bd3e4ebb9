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
    /// Learn in batches of VO targets that span `secs` seconds (learners
    /// that learn in batches, such as the streaming sparse GP, through
    /// [`ResidualRegressor::update_batch`]): a batch ends at the first
    /// target at least `secs` after the batch's first, and the first batch
    /// also waits for `min_targets` targets.
    Batch {
        /// Seconds of VO targets a batch spans.
        secs: f64,
        /// Fewest targets in the first batch (default 20).
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

/// A regressor learning from VO targets, behind [`ResidualSource`]: any
/// regressor (`M` unsized: a boxed trait object offline), or a concrete
/// type whose state the live node saves ([`OnlineLearner::model`]).
#[derive(Clone)]
pub struct OnlineLearner<M: ResidualRegressor + ?Sized = dyn ResidualRegressor> {
    name: String,
    model: Box<M>,
    mode: OnlineMode,
    prior_variance: f64,
    inputs: Vec<f64>,
    targets: Vec<f64>,
    n_inputs: Option<usize>,
    /// Targets learned so far, and the index of the first whose row is
    /// kept (a refit keeps every row; a batch learner the open batch's;
    /// one update per target none, so a learner running for hours does
    /// not grow).
    seen: usize,
    stored_from: usize,
    since_refit: usize,
    fitted: bool,
    /// `(time, targets so far)` after each target.
    history: Vec<(f64, usize)>,
    /// Whether the window inputs are z-scored already.
    inputs_standardized: bool,
    /// In [`OnlineMode::Batch`], the time of the open batch's first target
    /// and the index of its first row.
    open_batch: Option<(f64, usize)>,
    /// Whether the predicted mean is handed on (to correct the odometry).
    correct_mean: bool,
}

impl<M: ResidualRegressor + ?Sized> OnlineLearner<M> {
    /// Learns with `model` (fresh; it sees only VO targets) in `mode`;
    /// before it can predict, the prediction is zero mean with variance
    /// `prior_variance` per axis.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] when `mode` is `update` and the model
    /// cannot learn online, or a refit count is zero.
    pub fn new(
        name: impl Into<String>,
        model: Box<M>,
        mode: OnlineMode,
        prior_variance: f64,
    ) -> Result<Self, FrontendError> {
        match mode {
            OnlineMode::Update | OnlineMode::Batch { .. } if !model.supports_online_update() => {
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
            OnlineMode::Batch { secs, min_targets }
                if !(secs.is_finite() && secs > 0.0) || min_targets == 0 =>
            {
                return Err(FrontendError::InvalidConfig {
                    field: "online.batch_secs".into(),
                    expected: format!(
                        "a positive, finite number of seconds (found {secs}) and at least 1 \
                         target for the first batch"
                    ),
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
            seen: 0,
            stored_from: 0,
            since_refit: 0,
            fitted: false,
            history: Vec::new(),
            inputs_standardized: false,
            open_batch: None,
            correct_mean: true,
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

    /// Whether the model's predicted mean is handed on, to correct the
    /// odometry (the default); `false` hands on a zero mean with the
    /// model's variance, a control in which the learner only gates frames.
    #[must_use]
    pub fn with_mean_correction(mut self, correct_mean: bool) -> Self {
        self.correct_mean = correct_mean;
        self
    }

    /// The model as learned so far.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// Whether the model has learned before it is given here (a saved
    /// or checkpointed model going on learning): it predicts from the
    /// start rather than the prior.
    #[must_use]
    pub fn with_learned(mut self, learned: bool) -> Self {
        self.fitted = learned;
        self
    }

    /// The prediction on `window`'s inputs: the model's once it has
    /// learned, zero mean with the prior variance before.
    ///
    /// # Errors
    /// What the model reports.
    pub fn predict_window(
        &self,
        window: &TraverseWindow,
    ) -> Result<ResidualPrediction, FrontendError> {
        let uninformed = ResidualPrediction::uninformed(self.prior_variance);
        if !self.fitted {
            return Ok(uninformed);
        }
        let x = SampleMatrix::from_row_major(1, window.inputs.len(), window.inputs.clone())?;
        match self.model.predict(&x) {
            Ok(p) if !self.correct_mean => Ok(ResidualPrediction {
                mean: Vector3::zeros(),
                variance: Vector3::from_iterator(p.variance.row(0).iter().copied()),
                absolute: None,
            }),
            Ok(p) => Ok(ResidualPrediction {
                mean: Vector3::from_iterator(p.mean.row(0).iter().copied()),
                variance: Vector3::from_iterator(p.variance.row(0).iter().copied()),
                absolute: None,
            }),
            Err(Error::NotFitted { .. }) => Ok(uninformed),
            Err(e) => Err(e.into()),
        }
    }

    /// Targets learned so far.
    pub fn targets_seen(&self) -> usize {
        self.seen
    }

    /// `(time, targets so far)` after each target.
    pub fn history(&self) -> &[(f64, usize)] {
        &self.history
    }

    /// The targets from row `first` on, as a dataset.
    fn rows_from(&self, first: usize) -> Result<ResidualDataset, FrontendError> {
        let (n, d) = (self.seen - first, self.n_inputs.unwrap_or(0));
        let kept = first - self.stored_from;
        Ok(ResidualDataset::new(
            SampleMatrix::from_row_major(n, d, self.inputs[kept * d..].to_vec())?,
            SampleMatrix::from_row_major(n, 3, self.targets[kept * 3..].to_vec())?,
            (0..d).map(|i| format!("x{i}")).collect(),
            ["res_vx", "res_vy", "res_vz"].map(String::from).to_vec(),
        )?
        .with_standardized_inputs(self.inputs_standardized))
    }

    fn refit(&mut self) -> Result<(), FrontendError> {
        let data = self.rows_from(0)?;
        self.model.fit(&data)?;
        self.fitted = true;
        self.since_refit = 0;
        Ok(())
    }
}

impl<M: ResidualRegressor + ?Sized> ResidualSource for OnlineLearner<M> {
    fn name(&self) -> &str {
        &self.name
    }

    fn on_window(
        &mut self,
        _index: usize,
        window: &TraverseWindow,
    ) -> Result<ResidualPrediction, FrontendError> {
        self.predict_window(window)
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
        self.seen += 1;
        if matches!(self.mode, OnlineMode::Update) {
            self.stored_from = self.seen;
        } else {
            self.inputs.extend_from_slice(inputs);
            self.targets.extend(target.iter());
        }
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
            OnlineMode::Batch { secs, min_targets } => {
                let row = self.targets_seen() - 1;
                let (began, first) = *self.open_batch.get_or_insert((time_secs, row));
                let enough = self.fitted || self.targets_seen() >= min_targets;
                if time_secs - began >= secs && enough {
                    let batch = self.rows_from(first)?;
                    self.model.update_batch(&batch)?;
                    self.fitted = true;
                    self.open_batch = None;
                    self.inputs.clear();
                    self.targets.clear();
                    self.stored_from = self.seen;
                }
            }
        }
        self.history.push((time_secs, self.targets_seen()));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use std::sync::{Arc, Mutex};

    use gpodo_traits::{FitReport, Predictions};

    use super::*;

    /// Records the size of each batch it is given.
    struct Batches(Arc<Mutex<Vec<usize>>>);

    impl ResidualRegressor for Batches {
        fn name(&self) -> &str {
            "batches"
        }
        fn fit(&mut self, _: &ResidualDataset) -> Result<FitReport, Error> {
            unreachable!("a batch learner is never refitted")
        }
        /// A mean of 1 and a variance of 2 for every output.
        fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
            let n = inputs.nrows();
            Ok(Predictions {
                mean: SampleMatrix::from_row_major(n, 3, vec![1.0; 3 * n])?,
                variance: SampleMatrix::from_row_major(n, 3, vec![2.0; 3 * n])?,
            })
        }
        fn supports_online_update(&self) -> bool {
            true
        }
        fn update(&mut self, _: &[f64], _: &[f64]) -> Result<(), Error> {
            Ok(())
        }
        fn update_batch(&mut self, data: &ResidualDataset) -> Result<(), Error> {
            assert_eq!(
                data.inputs.row(0)[0],
                self.0.lock().unwrap().iter().sum::<usize>() as f64
            );
            self.0.lock().unwrap().push(data.len());
            Ok(())
        }
    }

    #[test]
    fn a_batch_spans_its_seconds_of_targets_and_the_first_waits_for_enough() {
        let sizes = Arc::new(Mutex::new(Vec::new()));
        let mode = OnlineMode::Batch {
            secs: 30.0,
            min_targets: 6,
        };
        let mut learner =
            OnlineLearner::new("b", Box::new(Batches(sizes.clone())), mode, 1e-4).unwrap();
        // A target every 8 s; row i has input i.
        for i in 0..20 {
            learner
                .on_target(&[i as f64, 0.0], &Vector3::zeros(), 8.0 * i as f64)
                .unwrap();
        }
        // The first batch: 0 s to 32 s is 5 targets, too few, so it runs
        // to the 6th (40 s); then 48 s to 80 s and 88 s to 120 s (the first
        // target 30 s after the batch's first ends it), and 128 s to 152 s
        // stays open.
        assert_eq!(*sizes.lock().unwrap(), vec![6, 5, 5]);
        assert_eq!(learner.targets_seen(), 20);
    }

    #[test]
    fn without_mean_correction_only_the_variance_is_handed_on() {
        let window = TraverseWindow {
            start_secs: 0.0,
            end_secs: 1.0,
            steps: 0..10,
            inputs: vec![0.5, 0.5],
            true_residual: Vector3::zeros(),
        };
        for (correct, mean) in [(true, 1.0), (false, 0.0)] {
            let model = Box::new(Batches(Arc::default()));
            let mut learner = OnlineLearner::new("b", model, OnlineMode::Update, 1e-4)
                .unwrap()
                .with_mean_correction(correct);
            let before = learner.on_window(0, &window).unwrap();
            assert_eq!(before.variance, Vector3::repeat(1e-4), "uninformed");
            learner
                .on_target(&[0.0, 0.0], &Vector3::zeros(), 1.0)
                .unwrap();
            let after = learner.on_window(1, &window).unwrap();
            assert_eq!(after.mean, Vector3::repeat(mean));
            assert_eq!(after.variance, Vector3::repeat(2.0));
        }
    }

    #[test]
    fn a_batch_of_no_seconds_is_refused() {
        let sizes = Arc::new(Mutex::new(Vec::new()));
        for secs in [0.0, -1.0, f64::NAN] {
            let mode = OnlineMode::Batch {
                secs,
                min_targets: 6,
            };
            let Err(FrontendError::InvalidConfig { field, .. }) =
                OnlineLearner::new("b", Box::new(Batches(sizes.clone())), mode, 1e-4)
            else {
                panic!("{secs} s accepted");
            };
            assert_eq!(field, "online.batch_secs");
        }
    }
}
