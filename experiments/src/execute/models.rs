//! `gpodo fit` and `gpodo predict`: a trained model out of an experiment
//! (the regressor of a given label fitted on the experiment's training rows,
//! saved as a [`ModelFile`] with the experiment's input z-scoring), and
//! predictions from a saved model on raw input rows read from CSV, matched
//! by column name.

use std::path::{Path, PathBuf};

use gpodo_regressors::metrics::Evaluation;
use gpodo_regressors::model_file::{ModelFile, ModelFileError, Provenance, RowRecipe};
use gpodo_testbed::sim::preset::SimulatorConfig;
use gpodo_traits::{Predictions, SampleMatrix};

use crate::config::{DatasetSpec, ExperimentConfig};
use crate::error::PipelineError;
use crate::execute::code_version;
use crate::execute::data::{model_rows, prepare};

/// A model fitted for saving, with what it predicts on the test rows.
#[derive(Debug)]
pub struct FittedModel {
    /// The model file.
    pub file: ModelFile,
    /// The test rows' raw (not z-scored) inputs, with their column names.
    pub test_inputs: (Vec<String>, SampleMatrix),
    /// The in-process model's predictions on the test rows.
    pub test_predictions: Predictions,
    /// Their scores.
    pub evaluation: Evaluation,
}

/// Why `gpodo fit` or `gpodo predict` failed.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The experiment's pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// No regressor of that label.
    #[error("no regressor labelled `{label}`; the experiment's regressors are: {}", labels.join(", "))]
    UnknownLabel {
        /// The label asked for.
        label: String,
        /// The labels there are.
        labels: Vec<String>,
    },
    /// Saving, loading or using the model failed.
    #[error(transparent)]
    ModelFile(#[from] ModelFileError),
    /// The input CSV could not be read.
    #[error("{}: {detail}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line where there is one.
        detail: String,
    },
}

/// Fits the regressor labelled `label` of `config` (relative paths against
/// `base`) on the training rows, as `gpodo run` fits it.
///
/// # Errors
/// [`ModelError`].
pub fn fit_model(config: &ExperimentConfig, label: &str) -> Result<FittedModel, ModelError> {
    let labels = config.regressor_labels();
    let index = labels
        .iter()
        .position(|l| l == label)
        .ok_or_else(|| ModelError::UnknownLabel {
            label: label.into(),
            labels: labels.clone(),
        })?;
    let spec = &config.regressors[index];
    let data = prepare(config)?;
    let (rows, scaler) = model_rows(&data)?;
    let provenance = Provenance {
        experiment: config.name.clone(),
        code_version: code_version(),
        training_rows: rows.train.len(),
    };
    crate::execute::fit::check_memory(
        spec,
        label,
        &rows.train,
        crate::util::memory::available_bytes(),
    )?;
    let (mut file, model) = ModelFile::fit(spec, &rows.train, Some(scaler), provenance)?;
    file.label = label.to_string();
    file.rows = row_recipe(config);
    let test_predictions =
        model
            .predict(&rows.test.inputs)
            .map_err(|source| PipelineError::Regressor {
                label: label.to_string(),
                source,
            })?;
    let evaluation = rows.score(&test_predictions)?;
    Ok(FittedModel {
        file,
        test_inputs: (data.test.input_names.clone(), data.test.inputs.clone()),
        test_predictions,
        evaluation,
    })
}

/// How `config` makes its input rows from a robot's streams, for the
/// model file; none when its rows come from a residual table.
pub fn row_recipe(config: &ExperimentConfig) -> Option<RowRecipe> {
    let rate_hz = match &config.dataset {
        DatasetSpec::ResidualTable { .. } => return None,
        DatasetSpec::Simulated { preset, seed, .. } => {
            Some(1.0 / SimulatorConfig::preset(*preset, *seed).dt_secs)
        }
        DatasetSpec::Logs { .. } => None,
        DatasetSpec::Bags { topics, .. } => Some(topics.rate_hz),
    };
    Some(RowRecipe {
        rate_hz,
        window_secs: config.residuals.window_secs,
        absolute_targets: config.residuals.absolute_targets,
        motion_model: serde_json::to_value(&config.motion_model).ok()?,
    })
}

/// Reads a CSV with a header row: the column names and the rows (every
/// value a number).
///
/// # Errors
/// [`ModelError::Csv`] naming the line and column.
pub fn read_rows(path: &Path) -> Result<(Vec<String>, SampleMatrix), ModelError> {
    let bad = |detail: String| ModelError::Csv {
        path: path.to_path_buf(),
        detail,
    };
    let mut reader = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    let names: Vec<String> = reader
        .headers()
        .map_err(|e| bad(e.to_string()))?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        let record = record.map_err(|e| bad(format!("line {line}: {e}")))?;
        let row = record
            .iter()
            .enumerate()
            .map(|(j, v)| {
                v.trim().parse::<f64>().map_err(|_| {
                    bad(format!(
                        "line {line}, column `{}`: `{v}` is not a number",
                        names.get(j).map_or("?", String::as_str)
                    ))
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        rows.push(row);
    }
    let matrix = SampleMatrix::from_rows(names.len(), &rows).map_err(|e| bad(e.to_string()))?;
    Ok((names, matrix))
}

/// Predicts with the model saved at `model` on the rows of `input` and
/// writes `mean_<target>` and `var_<target>` per row to `out`.
///
/// # Errors
/// [`ModelError`]; `out` is written only when every row was predicted.
pub fn predict_csv(model: &Path, input: &Path, out: &Path) -> Result<usize, ModelError> {
    let file = ModelFile::load(model)?;
    let (names, rows) = read_rows(input)?;
    let p = file.predictor()?.predict(&names, &rows)?;
    let mut header = Vec::new();
    for t in &file.target_names {
        header.push(format!("mean_{t}"));
    }
    for t in &file.target_names {
        header.push(format!("var_{t}"));
    }
    let mut text = header.join(",");
    text.push('\n');
    for i in 0..p.mean.nrows() {
        let values: Vec<String> = p
            .mean
            .row(i)
            .iter()
            .chain(p.variance.row(i))
            .map(|v| format!("{v:e}"))
            .collect();
        text.push_str(&values.join(","));
        text.push('\n');
    }
    crate::util::output::write_atomically(out, text.as_bytes()).map_err(|e| ModelError::Csv {
        path: out.to_path_buf(),
        detail: e.to_string(),
    })?;
    Ok(p.mean.nrows())
}
