//! Trained models out of an experiment: a versioned JSON file holding the
//! regressor's learned state, the names of the input and target columns
//! and the experiment's input z-scoring, so that a rover (or `gpodo
//! predict`) can load it and predict from raw input rows, matched by
//! column name.
//!
//! ```no_run
//! use gpodo_regressors::model_file::ModelFile;
//! use gpodo_traits::SampleMatrix;
//!
//! let model = ModelFile::load("model.gpodo".as_ref())?;
//! let columns = model.input_names.clone();           // or any superset, in any order
//! let rows = SampleMatrix::zeros(1, columns.len());  // raw (unscaled) inputs
//! let predicted = model.predictor()?.predict(&columns, &rows)?;
//! println!("{:?} ± {:?}", predicted.mean.row(0), predicted.variance.row(0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use std::sync::Arc;

use gpodo_traits::{
    FitProgress, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
    Standardizer,
};
use serde::{Deserialize, Serialize};

use crate::exact_gp::{ExactGp, ExactGpState};
use crate::ilgr::{Ilgr, IlgrState};
use crate::sparse_gp::{SparseGp, SparseGpState};
use crate::sparse_spectrum::{SparseSpectrumGp, SparseSpectrumState};
use crate::streaming_sparse_gp::{StreamingSparseGp, StreamingSparseGpState};
use crate::{RegressorError, RegressorSpec};

/// What the first field of every model file says.
pub const MODEL_FORMAT: &str = "gpodo-model";

/// The model-file version this build writes. It reads it, version 2
/// (which had no row recipe) and version 1 (whose GP settings had the
/// `hyperopt:` settings at their top level).
pub const MODEL_VERSION: u32 = 3;

/// A regressor's learned state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SavedState {
    /// An exact GP.
    ExactGp(ExactGpState),
    /// A sparse GP.
    SparseGp(SparseGpState),
    /// An ILGR (which can go on learning online after loading).
    Ilgr(IlgrState),
    /// A sparse-spectrum GP (which can go on learning online after loading).
    SparseSpectrum(Box<SparseSpectrumState>),
    /// A streaming sparse GP (which can go on learning online after
    /// loading, the unfinished batch's rows included).
    StreamingSparseGp(Box<StreamingSparseGpState>),
}

/// Where a saved model came from.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Provenance {
    /// The experiment's name.
    pub experiment: String,
    /// `git describe` of the code that trained it.
    pub code_version: String,
    /// Training rows.
    pub training_rows: usize,
}

/// How the model's input rows were made from a robot's streams, so that
/// rows can be made the same way from live messages: the experiment's
/// clock, window and motion model. A model fitted on a residual table has
/// none (its rows came ready-made).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RowRecipe {
    /// The clock the streams were resampled to (Hz): a bag import's
    /// `rate_hz`, the simulator's sensor rate; none for rover logs read as
    /// recorded.
    pub rate_hz: Option<f64>,
    /// Seconds each row averages (`residuals.window_secs`); none for one
    /// row per clock step.
    pub window_secs: Option<f64>,
    /// Whether the targets are |residual| (`residuals.absolute_targets`).
    pub absolute_targets: bool,
    /// The experiment's `motion_model:` block, its rover description's
    /// path as on the machine that trained the model (the robot gives its
    /// own).
    pub motion_model: serde_json::Value,
}

/// A trained model as saved on disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Always [`MODEL_FORMAT`].
    pub format: String,
    /// [`MODEL_VERSION`] when written.
    pub version: u32,
    /// The regressor's label in the experiment.
    pub label: String,
    /// The input columns the model reads, in its order.
    pub input_names: Vec<String>,
    /// The outputs it predicts.
    pub target_names: Vec<String>,
    /// The experiment's z-scoring of the raw inputs (applied before the
    /// model), when it z-scored them.
    pub input_standardizer: Option<Standardizer>,
    /// Where it came from.
    pub provenance: Provenance,
    /// How its input rows were made (none before version 3, and for rows
    /// read from a residual table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rows: Option<RowRecipe>,
    /// The learned state.
    pub state: SavedState,
}

/// Why a model file could not be written, read or used.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a whole model file of this version.
    #[error("{}: {detail}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// The rows to predict lack a column the model reads.
    #[error("the input rows have no column `{column}` (the model reads {expected:?})")]
    MissingColumn {
        /// The missing column.
        column: String,
        /// Every column the model reads.
        expected: Vec<String>,
    },
    /// This regressor kind cannot be saved.
    #[error("regressor `{label}` cannot be saved: {why}")]
    NotSavable {
        /// Its label.
        label: String,
        /// Why.
        why: String,
    },
    /// Fitting, rebuilding or predicting failed.
    #[error(transparent)]
    Regressor(#[from] RegressorError),
    /// The model refused the rows.
    #[error(transparent)]
    Model(#[from] gpodo_traits::Error),
}

impl ModelFile {
    /// Fits `spec` on `train` (inputs already z-scored with
    /// `input_standardizer` when one is given) and returns its model file
    /// and the fitted model itself.
    ///
    /// # Errors
    /// [`ModelFileError::NotSavable`] for kinds without a saved state
    /// (`zero`, `knn`, `external`: the plugin owns its state), or the fit's
    /// error.
    pub fn fit(
        spec: &RegressorSpec,
        train: &ResidualDataset,
        input_standardizer: Option<Standardizer>,
        provenance: Provenance,
    ) -> Result<(Self, Box<dyn ResidualRegressor>), ModelFileError> {
        let (file, model, _) =
            Self::fit_with_progress(spec, train, input_standardizer, provenance, None)?;
        Ok((file, model))
    }

    /// [`Self::fit`], reporting the optimiser's iterations to `progress`
    /// (which may stop the fit), and returning the fit's report too.
    ///
    /// # Errors
    /// As [`Self::fit`].
    pub fn fit_with_progress(
        spec: &RegressorSpec,
        train: &ResidualDataset,
        input_standardizer: Option<Standardizer>,
        provenance: Provenance,
        progress: Option<Arc<dyn FitProgress>>,
    ) -> Result<(Self, Box<dyn ResidualRegressor>, FitReport), ModelFileError> {
        let (state, model, report): (Option<SavedState>, Box<dyn ResidualRegressor>, FitReport) =
            match spec {
                RegressorSpec::ExactGp(p) => {
                    let mut m = ExactGp::new(p.clone())?;
                    m.set_progress(progress);
                    let report = m.fit(train)?;
                    (
                        m.state().cloned().map(SavedState::ExactGp),
                        Box::new(m),
                        report,
                    )
                }
                RegressorSpec::SparseGp(p) => {
                    let mut m = SparseGp::new(p.clone())?;
                    m.set_progress(progress);
                    let report = m.fit(train)?;
                    (
                        m.state().cloned().map(SavedState::SparseGp),
                        Box::new(m),
                        report,
                    )
                }
                RegressorSpec::Ilgr(p) => {
                    let mut m = Ilgr::new(p.clone())?;
                    m.set_progress(progress);
                    let report = m.fit(train)?;
                    (
                        m.state().cloned().map(SavedState::Ilgr),
                        Box::new(m),
                        report,
                    )
                }
                RegressorSpec::SparseSpectrum(p) => {
                    let mut m = SparseSpectrumGp::new(p.clone())?;
                    m.set_progress(progress);
                    let report = m.fit(train)?;
                    let state = m
                        .state()
                        .cloned()
                        .map(|s| SavedState::SparseSpectrum(Box::new(s)));
                    (state, Box::new(m), report)
                }
                RegressorSpec::StreamingSparseGp(p) => {
                    let mut m = StreamingSparseGp::new(p.clone())?;
                    m.set_progress(progress);
                    let report = m.fit(train)?;
                    let state = m
                        .state()
                        .cloned()
                        .map(|s| SavedState::StreamingSparseGp(Box::new(s)));
                    (state, Box::new(m), report)
                }
                RegressorSpec::Zero { .. } | RegressorSpec::Knn(_) | RegressorSpec::External(_) => {
                    return Err(ModelFileError::NotSavable {
                        label: spec.label(),
                        why: "only exact_gp, sparse_gp, ilgr, sparse_spectrum and streaming_sparse_gp models can be saved"
                            .into(),
                    });
                }
            };
        let state = state.ok_or_else(|| ModelFileError::NotSavable {
            label: spec.label(),
            why: "the fit left no state".into(),
        })?;
        let file = Self {
            format: MODEL_FORMAT.into(),
            version: MODEL_VERSION,
            label: spec.label(),
            input_names: train.input_names.clone(),
            target_names: train.target_names.clone(),
            input_standardizer,
            provenance,
            rows: None,
            state,
        };
        Ok((file, model, report))
    }

    /// Writes the file (to a temporary name, then renamed, so that an
    /// interrupted save never leaves a half-written model under `path`).
    ///
    /// # Errors
    /// [`ModelFileError::Io`].
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        let io = |source| ModelFileError::Io {
            path: path.to_path_buf(),
            source,
        };
        let text = serde_json::to_string(self).map_err(|e| io(std::io::Error::other(e)))?;
        let tmp = path.with_extension("gpodo.partial");
        let written =
            std::fs::write(&tmp, text.as_bytes()).and_then(|()| std::fs::rename(&tmp, path));
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        written.map_err(io)
    }

    /// Reads a model file, refusing one of another format or version, a
    /// truncated one, or one whose parts disagree.
    ///
    /// # Errors
    /// [`ModelFileError::Io`] or [`ModelFileError::Invalid`] naming the file.
    pub fn load(path: &Path) -> Result<Self, ModelFileError> {
        let invalid = |detail: String| ModelFileError::Invalid {
            path: path.to_path_buf(),
            detail,
        };
        let text = std::fs::read_to_string(path).map_err(|source| ModelFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        // The header first, so that another version is named as such.
        #[derive(Deserialize)]
        struct Header {
            format: Option<String>,
            version: Option<u32>,
        }
        let header: Header = serde_json::from_str(&text).map_err(|e| {
            if e.is_eof() {
                invalid(format!("truncated ({e}); save the model again"))
            } else {
                invalid(format!("not a gpodo model file ({e})"))
            }
        })?;
        if header.format.as_deref() != Some(MODEL_FORMAT) {
            return Err(invalid(format!(
                "not a gpodo model file (`format` is {:?}, expected \"{MODEL_FORMAT}\")",
                header.format
            )));
        }
        let mut value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| invalid(e.to_string()))?;
        match header.version {
            Some(MODEL_VERSION) => {}
            Some(2) => value["version"] = serde_json::Value::from(MODEL_VERSION),
            Some(1) => upgrade_v1(&mut value),
            other => {
                let version = other.map_or("without a version".into(), |v| format!("version {v}"));
                return Err(invalid(format!(
                    "model file {version}; this gpodo reads versions 1 to {MODEL_VERSION} (save the model again with this version)"
                )));
            }
        }
        let file: Self = serde_json::from_value(value).map_err(|e| invalid(e.to_string()))?;
        let d = file.input_names.len();
        if let Some(s) = &file.input_standardizer
            && s.dim() != d
        {
            return Err(invalid(format!(
                "the input standardizer has {} columns, the model reads {d}",
                s.dim()
            )));
        }
        Ok(file)
    }

    /// The model, rebuilt to predict (and, for ILGR, to go on learning).
    ///
    /// # Errors
    /// [`ModelFileError::Regressor`] when the saved state is inconsistent.
    pub fn predictor(&self) -> Result<Predictor, ModelFileError> {
        let model = match &self.state {
            SavedState::ExactGp(s) => Rebuilt::ExactGp(Box::new(ExactGp::from_state(s.clone())?)),
            SavedState::SparseGp(s) => {
                Rebuilt::SparseGp(Box::new(SparseGp::from_state(s.clone())?))
            }
            SavedState::Ilgr(s) => Rebuilt::Ilgr(Box::new(Ilgr::from_state(s.clone())?)),
            SavedState::SparseSpectrum(s) => {
                Rebuilt::SparseSpectrum(Box::new(SparseSpectrumGp::from_state(s.as_ref().clone())?))
            }
            SavedState::StreamingSparseGp(s) => Rebuilt::StreamingSparseGp(Box::new(
                StreamingSparseGp::from_state(s.as_ref().clone())?,
            )),
        };
        Ok(Predictor {
            model,
            input_names: self.input_names.clone(),
            input_standardizer: self.input_standardizer.clone(),
        })
    }
}

/// A model rebuilt from its saved state (boxed: the kinds differ in size).
enum Rebuilt {
    ExactGp(Box<ExactGp>),
    SparseGp(Box<SparseGp>),
    Ilgr(Box<Ilgr>),
    SparseSpectrum(Box<SparseSpectrumGp>),
    StreamingSparseGp(Box<StreamingSparseGp>),
}

/// A loaded model that predicts from raw input rows.
pub struct Predictor {
    model: Rebuilt,
    input_names: Vec<String>,
    input_standardizer: Option<Standardizer>,
}

impl Predictor {
    /// Mean and variance for each row of `rows`, whose columns are named
    /// `columns` (any order, extra columns ignored), in raw units.
    ///
    /// # Errors
    /// [`ModelFileError::MissingColumn`] naming the first missing column,
    /// or the model's error.
    pub fn predict(
        &self,
        columns: &[String],
        rows: &SampleMatrix,
    ) -> Result<Predictions, ModelFileError> {
        let inputs = self.model_inputs(columns, rows)?;
        Ok(self.model_ref().predict(&inputs)?)
    }

    /// [`Self::predict`], with the latent function's variance beside the
    /// noisy target's (`None` for a model without one: ILGR).
    ///
    /// # Errors
    /// As [`Self::predict`].
    pub fn predict_with_latent(
        &self,
        columns: &[String],
        rows: &SampleMatrix,
    ) -> Result<(Predictions, Option<SampleMatrix>), ModelFileError> {
        let inputs = self.model_inputs(columns, rows)?;
        let full = match &self.model {
            Rebuilt::ExactGp(m) => m.predict_full(&inputs)?,
            Rebuilt::SparseGp(m) => m.predict_full(&inputs)?,
            Rebuilt::Ilgr(m) => return Ok((m.predict(&inputs)?, None)),
            Rebuilt::SparseSpectrum(m) => return Ok((m.predict(&inputs)?, None)),
            Rebuilt::StreamingSparseGp(m) => return Ok((m.predict(&inputs)?, None)),
        };
        let predictions = Predictions {
            mean: full.mean,
            variance: full.variance,
        };
        Ok((predictions, Some(full.latent_variance)))
    }

    /// The model's learned state now (after online updates, for ILGR), to
    /// save it again.
    pub fn saved_state(&self) -> Option<SavedState> {
        match &self.model {
            Rebuilt::ExactGp(m) => m.state().cloned().map(SavedState::ExactGp),
            Rebuilt::SparseGp(m) => m.state().cloned().map(SavedState::SparseGp),
            Rebuilt::Ilgr(m) => m.state().cloned().map(SavedState::Ilgr),
            Rebuilt::SparseSpectrum(m) => m
                .state()
                .cloned()
                .map(|s| SavedState::SparseSpectrum(Box::new(s))),
            Rebuilt::StreamingSparseGp(m) => m
                .state()
                .cloned()
                .map(|s| SavedState::StreamingSparseGp(Box::new(s))),
        }
    }

    /// The log marginal likelihood of each output group of an exact GP
    /// (standardised units); `None` for other kinds.
    pub fn log_marginal_likelihoods(&self) -> Option<Vec<f64>> {
        match &self.model {
            Rebuilt::ExactGp(m) => Some(m.log_marginal_likelihoods()),
            Rebuilt::SparseGp(_)
            | Rebuilt::Ilgr(_)
            | Rebuilt::SparseSpectrum(_)
            | Rebuilt::StreamingSparseGp(_) => None,
        }
    }

    fn model_ref(&self) -> &dyn ResidualRegressor {
        match &self.model {
            Rebuilt::ExactGp(m) => m.as_ref(),
            Rebuilt::SparseGp(m) => m.as_ref(),
            Rebuilt::Ilgr(m) => m.as_ref(),
            Rebuilt::SparseSpectrum(m) => m.as_ref(),
            Rebuilt::StreamingSparseGp(m) => m.as_ref(),
        }
    }

    /// The model's inputs for `rows` whose columns are named `columns`:
    /// its columns picked by name, z-scored as the file says.
    ///
    /// # Errors
    /// [`ModelFileError::MissingColumn`].
    pub fn model_inputs(
        &self,
        columns: &[String],
        rows: &SampleMatrix,
    ) -> Result<SampleMatrix, ModelFileError> {
        let index: Vec<usize> = self
            .input_names
            .iter()
            .map(|name| {
                columns.iter().position(|c| c == name).ok_or_else(|| {
                    ModelFileError::MissingColumn {
                        column: name.clone(),
                        expected: self.input_names.clone(),
                    }
                })
            })
            .collect::<Result<_, _>>()?;
        let picked: Vec<Vec<f64>> = rows
            .rows()
            .map(|r| index.iter().map(|&j| r[j]).collect())
            .collect();
        let mut inputs = SampleMatrix::from_rows(index.len(), &picked)?;
        if let Some(s) = &self.input_standardizer {
            inputs = s.transform(&inputs)?;
        }
        Ok(inputs)
    }

    /// The rebuilt model (e.g. to continue learning online with `update`,
    /// on inputs z-scored as the file says).
    pub fn model_mut(&mut self) -> &mut dyn ResidualRegressor {
        match &mut self.model {
            Rebuilt::ExactGp(m) => m.as_mut(),
            Rebuilt::SparseGp(m) => m.as_mut(),
            Rebuilt::Ilgr(m) => m.as_mut(),
            Rebuilt::SparseSpectrum(m) => m.as_mut(),
            Rebuilt::StreamingSparseGp(m) => m.as_mut(),
        }
    }
}

/// Rewrites a version-1 file as the current version: a GP's optimiser
/// settings move from the top level of its `params` into
/// `params.hyperopt` (version 2), and it has no row recipe (version 3).
/// Version 1 of the other kinds reads as it is.
fn upgrade_v1(value: &mut serde_json::Value) {
    use serde_json::{Map, Value};
    if let Some(version) = value.get_mut("version") {
        *version = Value::from(MODEL_VERSION);
    }
    let Some(Value::Object(params)) = value.pointer_mut("/state/params") else {
        return;
    };
    let mut hyperopt = Map::new();
    for key in crate::hyperopt::HYPEROPT_FIELDS {
        if let Some(v) = params.remove(key) {
            hyperopt.insert(key.to_string(), v);
        }
    }
    if !hyperopt.is_empty() {
        params.insert("hyperopt".into(), Value::Object(hyperopt));
    }
}
