//! The online learner run live: frontends' [`OnlineLearner`] over an
//! [`OnlineModel`], learning the gate's VO targets, predicting on the
//! node's rows, and checkpointed so that a restart resumes it.
//!
//! It starts from a saved model of an online kind (`--model`), from a
//! checkpoint of the same rover, columns and kind, or empty; before it
//! has learned anything it predicts a zero residual with the prior
//! variance, so a gate on its variance asks for frames often.

use std::path::Path;

use gpodo_frontends::FrontendError;
use gpodo_frontends::online::{OnlineLearner, OnlineMode};
use gpodo_frontends::prediction::{ResidualPrediction, ResidualSource as _};
use gpodo_frontends::traverse::TraverseWindow;
use gpodo_frontends::vo_target::VoTarget;
use gpodo_regressors::model_file::{MODEL_FORMAT, MODEL_VERSION, ModelFile, Provenance, RowRecipe};
use gpodo_regressors::online_model::OnlineModel;
use gpodo_traits::{SampleMatrix, Standardizer};
use nalgebra::Vector3;

use crate::checkpoint::{Checkpoint, CheckpointError, CheckpointKey};

/// What the learner's rows are and where it stands.
#[derive(Debug, Clone, PartialEq)]
pub struct LearnerIdentity {
    /// The model's label.
    pub label: String,
    /// The input columns, in the model's order.
    pub input_names: Vec<String>,
    /// The z-scoring applied to a row before the model (a saved model's).
    pub input_standardizer: Option<Standardizer>,
    /// How the rows are made (window, clock, motion model).
    pub rows: Option<RowRecipe>,
    /// The rover description's SHA-256.
    pub rover_sha256: String,
}

impl LearnerIdentity {
    /// The identity of a learner going on from the saved model `file`: its
    /// label, columns, z-scoring and row recipe.
    pub fn of_saved_model(file: &ModelFile, rover_sha256: String) -> Self {
        Self {
            label: file.label.clone(),
            input_names: file.input_names.clone(),
            input_standardizer: file.input_standardizer.clone(),
            rows: file.rows.clone(),
            rover_sha256,
        }
    }
}

/// Where the learner started from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LearnerStart {
    /// Empty.
    Empty,
    /// A saved model of an online kind.
    SavedModel,
    /// A checkpoint, with its count of targets learned.
    Checkpoint(u64),
}

/// The learner.
#[derive(Clone)]
pub struct LiveLearner {
    learner: OnlineLearner<OnlineModel>,
    identity: LearnerIdentity,
    /// Targets learned before this process started (from a checkpoint).
    resumed_targets: u64,
    start: LearnerStart,
}

impl LiveLearner {
    /// A learner of `model` (fresh, or rebuilt from a saved state) in
    /// `mode`, predicting a zero residual with `prior_variance` per axis
    /// until it has learned.
    ///
    /// # Errors
    /// What [`OnlineLearner::new`] reports for a mode the model cannot
    /// learn in.
    pub fn new(
        model: OnlineModel,
        mode: OnlineMode,
        prior_variance: f64,
        identity: LearnerIdentity,
        start: LearnerStart,
    ) -> Result<Self, FrontendError> {
        let standardized = identity.input_standardizer.is_some();
        let learned = !matches!(start, LearnerStart::Empty);
        let learner = OnlineLearner::new(
            identity.label.clone(),
            Box::new(model),
            mode,
            prior_variance,
        )?
        .with_standardized_inputs(standardized)
        .with_learned(learned);
        let resumed_targets = match start {
            LearnerStart::Checkpoint(n) => n,
            LearnerStart::Empty | LearnerStart::SavedModel => 0,
        };
        Ok(Self {
            learner,
            identity,
            resumed_targets,
            start,
        })
    }

    /// A learner that goes on from a saved model of an online kind (the
    /// `--model` given to the node), with its columns, z-scoring and row
    /// recipe, on the rover whose description's SHA-256 is
    /// `rover_sha256`.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] naming the model's kind when it
    /// does not learn online, or its state when it cannot be rebuilt;
    /// what [`OnlineLearner::new`] reports.
    pub fn from_saved_model(
        file: &ModelFile,
        mode: OnlineMode,
        prior_variance: f64,
        rover_sha256: String,
    ) -> Result<Self, FrontendError> {
        let model = OnlineModel::from_state(&file.state).map_err(|e| {
            FrontendError::InvalidConfig {
                field: "model".into(),
                expected: format!(
                    "a saved model of an online kind to go on learning from ({e}); otherwise the learner starts empty"
                ),
            }
        })?;
        let identity = LearnerIdentity::of_saved_model(file, rover_sha256);
        Self::new(
            model,
            mode,
            prior_variance,
            identity,
            LearnerStart::SavedModel,
        )
    }

    /// Resumes the checkpoint at `path`, refused unless it was written for
    /// this rover, these columns and this kind.
    ///
    /// # Errors
    /// [`CheckpointError`] for a file that cannot be read, is not a
    /// checkpoint, or does not match (naming the field); a state that
    /// cannot be rebuilt as [`CheckpointError::Invalid`].
    pub fn resume(
        path: &Path,
        mode: OnlineMode,
        prior_variance: f64,
        identity: LearnerIdentity,
        kind: &str,
    ) -> Result<Self, CheckpointError> {
        let checkpoint = Checkpoint::read(path)?;
        let key = CheckpointKey {
            rover_sha256: identity.rover_sha256.clone(),
            input_columns: identity.input_names.clone(),
            kind: kind.to_string(),
        };
        checkpoint.check(path, &key)?;
        let invalid = |detail: String| CheckpointError::Invalid {
            path: path.to_path_buf(),
            detail,
        };
        let model = OnlineModel::from_state(&checkpoint.model.state)
            .map_err(|e| invalid(format!("its model cannot be rebuilt: {e}")))?;
        Self::new(
            model,
            mode,
            prior_variance,
            identity,
            LearnerStart::Checkpoint(checkpoint.targets_learned),
        )
        .map_err(|e| invalid(e.to_string()))
    }

    /// The input columns, in the model's order.
    pub fn input_names(&self) -> &[String] {
        &self.identity.input_names
    }

    /// Where it started from.
    pub fn start(&self) -> LearnerStart {
        self.start
    }

    /// Targets learned, counting those before a resumed checkpoint.
    pub fn targets_learned(&self) -> u64 {
        self.resumed_targets + self.learner.targets_seen() as u64
    }

    /// Learns one target (its inputs raw, as the node's rows are).
    ///
    /// # Errors
    /// What the model reports.
    pub fn learn(&mut self, target: &VoTarget) -> Result<(), FrontendError> {
        let inputs = self.standardize(&target.inputs)?;
        self.learner
            .on_target(&inputs, &target.residual, target.time_secs)
    }

    /// The prediction on a raw row: the model's once it has learned, the
    /// prior before.
    ///
    /// # Errors
    /// What the model reports.
    pub fn predict(&self, row: &[f64]) -> Result<ResidualPrediction, FrontendError> {
        let window = TraverseWindow {
            start_secs: 0.0,
            end_secs: 0.0,
            steps: 0..0,
            inputs: self.standardize(row)?,
            true_residual: Vector3::zeros(),
        };
        self.learner.predict_window(&window)
    }

    /// The row z-scored as the model's inputs are (the saved model's
    /// standardizer), or as it is.
    fn standardize(&self, row: &[f64]) -> Result<Vec<f64>, FrontendError> {
        match &self.identity.input_standardizer {
            Some(s) => {
                let x = SampleMatrix::from_row_major(1, row.len(), row.to_vec())?;
                Ok(s.transform(&x)?.row(0).to_vec())
            }
            None => Ok(row.to_vec()),
        }
    }

    /// The learner's model as a model file (`None` before it has learned).
    pub fn model_file(&self) -> Option<ModelFile> {
        let state = self.learner.model().saved_state()?;
        Some(ModelFile {
            format: MODEL_FORMAT.into(),
            version: MODEL_VERSION,
            label: self.identity.label.clone(),
            input_names: self.identity.input_names.clone(),
            target_names: ["res_vx", "res_vy", "res_vz"].map(String::from).to_vec(),
            input_standardizer: self.identity.input_standardizer.clone(),
            provenance: Provenance {
                experiment: "gpodo live".into(),
                code_version: String::new(),
                training_rows: self.targets_learned() as usize,
            },
            rows: self.identity.rows.clone(),
            state,
        })
    }

    /// Writes a checkpoint to `path` atomically; nothing is written before
    /// the learner has learned.
    ///
    /// # Errors
    /// [`CheckpointError::Io`]; the previous checkpoint is then intact.
    pub fn checkpoint(&self, path: &Path) -> Result<bool, CheckpointError> {
        let Some(model) = self.model_file() else {
            return Ok(false);
        };
        Checkpoint::new(
            model,
            self.identity.rover_sha256.clone(),
            self.targets_learned(),
        )
        .write(path)?;
        Ok(true)
    }
}
