//! Runs one experiment: data → motion model → residual dataset →
//! regressors → evaluation on the held-out runs.

use std::path::{Path, PathBuf};
use std::time::Instant;

use gpodo_datasets::log::{RoverLog, read_log_csv};
use gpodo_datasets::residuals::residual_dataset;
use gpodo_datasets::sim::preset::SimulatorConfig;
use gpodo_datasets::standardize::Standardizer;
use gpodo_datasets::table::{TableSpec, read_residual_table, split_fraction};
use gpodo_kinematics::{RoverDescription, SkidSteerModel, WeightedJacobianModel};
use gpodo_regressors::metrics::{Evaluation, evaluate};
use gpodo_traits::{FitReport, MotionModel, ResidualDataset, ResidualRegressor};
use serde::{Deserialize, Serialize};

use crate::calibration::{ResidualStatistics, residual_statistics};
use crate::config::{DatasetSpec, ExperimentConfig, MotionModelSpec};
use crate::odometry::{DeadReckoning, dead_reckoning};
use crate::shared::SharedWork;
use crate::table_two::SchemeResult;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::traverse::Traverse;

/// A run's length and duration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Run name.
    pub name: String,
    /// Sensor samples.
    pub samples: usize,
    /// Duration (s).
    pub duration_secs: f64,
    /// Ground-truth path length (m).
    pub path_length_m: f64,
}

/// What the data were.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetSummary {
    /// Human-readable source.
    pub source: String,
    /// Training runs (empty for residual tables).
    pub train_runs: Vec<RunSummary>,
    /// Test runs (empty for residual tables).
    pub test_runs: Vec<RunSummary>,
    /// Training rows.
    pub n_train: usize,
    /// Test rows.
    pub n_test: usize,
    /// Input column names.
    pub input_names: Vec<String>,
    /// Target column names.
    pub target_names: Vec<String>,
    /// Steepest slope of a simulated terrain (deg).
    pub terrain_max_slope_deg: Option<f64>,
}

/// One regressor's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegressorResult {
    /// Label for tables.
    pub label: String,
    /// Its specification.
    pub spec: gpodo_regressors::RegressorSpec,
    /// What the fit did.
    pub fit: FitReport,
    /// Scores on the test rows.
    pub evaluation: Evaluation,
}

/// Everything an experiment produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExperimentResults {
    /// The resolved configuration.
    pub config: ExperimentConfig,
    /// `git describe` of the code, or the crate version.
    pub code_version: String,
    /// The data.
    pub dataset: DatasetSummary,
    /// The motion model's name (none for residual tables).
    pub motion_model: Option<String>,
    /// Dead reckoning with the motion model on each test run.
    pub dead_reckoning: Vec<(String, DeadReckoning)>,
    /// Residual statistics of the training and test rows.
    pub train_statistics: ResidualStatistics,
    /// Residual statistics of the test rows.
    pub test_statistics: ResidualStatistics,
    /// The same statistics of a reference table, when one was given.
    pub reference_statistics: Option<(String, ResidualStatistics)>,
    /// One entry per regressor, in config order.
    pub regressors: Vec<RegressorResult>,
    /// Table II: every scheme on every test run.
    #[serde(default)]
    pub schemes: Vec<SchemeResult>,
    /// Wall-clock duration of the whole experiment (s).
    pub duration_secs: f64,
    /// The training rows (physical units), written as a CSV beside the
    /// report.
    #[serde(skip)]
    pub train_rows: Option<ResidualDataset>,
    /// The test rows (physical units).
    #[serde(skip)]
    pub test_rows: Option<ResidualDataset>,
    /// The test runs as the front end saw them (for trajectories and plots).
    #[serde(skip)]
    pub traverses: std::sync::Arc<Vec<Traverse>>,
    /// Each regressor's window predictions on each traverse, where computed
    /// (`[regressor][traverse]`).
    #[serde(skip)]
    pub window_predictions: Vec<Option<Vec<Vec<ResidualPrediction>>>>,
}

/// Why an experiment failed.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading or simulating data failed.
    #[error(transparent)]
    Dataset(#[from] gpodo_datasets::DatasetError),
    /// The rover description or motion model is invalid.
    #[error(transparent)]
    Kinematics(#[from] gpodo_kinematics::KinematicsError),
    /// A regressor failed.
    #[error("regressor `{label}`: {source}")]
    Regressor {
        /// The regressor.
        label: String,
        /// What failed.
        source: gpodo_traits::Error,
    },
    /// Building or scoring a regressor failed.
    #[error(transparent)]
    Spec(#[from] gpodo_regressors::RegressorError),
    /// A model failed on a sample.
    #[error(transparent)]
    Model(#[from] gpodo_traits::Error),
    /// Training and test rows do not have the same columns, or a scheme
    /// refers to something that is not there.
    #[error("inconsistent experiment: {0}")]
    Inconsistent(String),
    /// The visual front end failed.
    #[error(transparent)]
    Frontend(#[from] gpodo_frontends::FrontendError),
    /// A scheme of Table II failed.
    #[error("scheme `{label}`: {source}")]
    Scheme {
        /// The scheme.
        label: String,
        /// What failed.
        source: Box<PipelineError>,
    },
}

fn resolve(base: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}

fn summarize(log: &RoverLog) -> RunSummary {
    RunSummary {
        name: log.name.clone(),
        samples: log.samples.len(),
        duration_secs: log.duration_secs(),
        path_length_m: log.path_length_m(),
    }
}

/// The code version: `git describe --always --dirty` when available.
pub fn code_version() -> String {
    std::process::Command::new("git")
        .args(["describe", "--always", "--dirty"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| env!("CARGO_PKG_VERSION").to_string())
}

/// The motion model of `spec` and the rover it describes.
fn motion_model(
    spec: &MotionModelSpec,
    base: &Path,
) -> Result<(Box<dyn MotionModel>, RoverDescription), PipelineError> {
    let load = |rover: &Option<PathBuf>| match rover {
        Some(p) => RoverDescription::from_path(&resolve(base, p)),
        None => Ok(RoverDescription::exoter()),
    };
    Ok(match spec {
        MotionModelSpec::WeightedJacobian { rover, config } => {
            let d = load(rover)?;
            (Box::new(WeightedJacobianModel::new(d.clone(), *config)?), d)
        }
        MotionModelSpec::SkidSteer { rover, yaw } => {
            let d = load(rover)?;
            (Box::new(SkidSteerModel::from_description(&d, *yaw)?), d)
        }
    })
}

/// Train/test rows plus what the report says about where they came from.
pub(crate) struct PreparedData {
    pub(crate) train: ResidualDataset,
    pub(crate) test: ResidualDataset,
    pub(crate) summary: DatasetSummary,
    pub(crate) motion_model: Option<String>,
    pub(crate) dead_reckoning: Vec<(String, DeadReckoning)>,
    /// The test runs (in the rover's joint order), the motion model and the
    /// wheel radius, for the front end.
    pub(crate) test_logs: Vec<RoverLog>,
    pub(crate) model: Option<(Box<dyn MotionModel>, f64)>,
}

fn refs(logs: &[RoverLog]) -> Vec<&RoverLog> {
    logs.iter().collect()
}

fn from_logs(
    config: &ExperimentConfig,
    base: &Path,
    train_logs: &[RoverLog],
    test_logs: &[RoverLog],
    source: String,
    terrain_max_slope_deg: Option<f64>,
) -> Result<PreparedData, PipelineError> {
    let (model, rover) = motion_model(&config.motion_model, base)?;
    // Models read joints by position: put every log in the rover's order.
    let in_rover_order = |logs: &[RoverLog]| {
        logs.iter()
            .map(|l| {
                l.with_joint_order(
                    &rover.wheel_names(),
                    &rover.steer_names(),
                    &rover.bogie_names(),
                )
            })
            .collect::<Result<Vec<_>, _>>()
    };
    let (train_logs, test_logs) = (&in_rover_order(train_logs)?, &in_rover_order(test_logs)?);
    let radius = rover.wheel_radius_m;
    let train = residual_dataset(&refs(train_logs), model.as_ref(), radius, &config.residuals)?;
    let test = residual_dataset(&refs(test_logs), model.as_ref(), radius, &config.residuals)?;
    let dead_reckoning = test_logs
        .iter()
        .map(|log| Ok((log.name.clone(), dead_reckoning(log, model.as_ref())?)))
        .collect::<Result<_, PipelineError>>()?;
    let test_logs = test_logs.clone();
    Ok(PreparedData {
        summary: DatasetSummary {
            source,
            train_runs: train_logs.iter().map(summarize).collect(),
            test_runs: test_logs.iter().map(summarize).collect(),
            n_train: train.len(),
            n_test: test.len(),
            input_names: train.input_names.clone(),
            target_names: train.target_names.clone(),
            terrain_max_slope_deg,
        },
        train,
        test,
        motion_model: Some(model.name().to_string()),
        dead_reckoning,
        test_logs,
        model: Some((model, radius)),
    })
}

pub(crate) fn prepare(
    config: &ExperimentConfig,
    base: &Path,
) -> Result<PreparedData, PipelineError> {
    match &config.dataset {
        DatasetSpec::Simulated {
            preset,
            seed,
            training_runs,
            training_run_secs,
            test_max_secs,
        } => {
            let mut sim = SimulatorConfig::preset(*preset, *seed);
            if let Some(n) = training_runs {
                sim.training_runs = *n;
            }
            if let Some(s) = training_run_secs {
                sim.training_run_secs = *s;
            }
            if let Some(s) = test_max_secs {
                sim.test_max_secs = *s;
            }
            tracing::info!(seed, "simulating the testbed");
            let testbed = sim.simulate()?;
            let source = format!("simulated `{}` testbed, seed {seed}", preset.name());
            from_logs(
                config,
                base,
                &testbed.train,
                &testbed.test,
                source,
                Some(testbed.terrain.max_slope_deg()),
            )
        }
        DatasetSpec::Logs { train, test } => {
            let read = |paths: &[PathBuf]| {
                paths
                    .iter()
                    .map(|p| read_log_csv(&resolve(base, p)))
                    .collect::<Result<Vec<_>, _>>()
            };
            let (train, test) = (read(train)?, read(test)?);
            from_logs(config, base, &train, &test, "rover logs".into(), None)
        }
        DatasetSpec::ResidualTable {
            path,
            inputs,
            targets,
            train_fraction,
        } => {
            let spec = TableSpec {
                inputs: inputs.clone(),
                targets: targets.clone(),
            };
            let data = read_residual_table(&resolve(base, path), &spec)?;
            let (train, test) = split_fraction(&data, *train_fraction)?;
            Ok(PreparedData {
                summary: DatasetSummary {
                    source: format!("residual table {}", path.display()),
                    train_runs: Vec::new(),
                    test_runs: Vec::new(),
                    n_train: train.len(),
                    n_test: test.len(),
                    input_names: train.input_names.clone(),
                    target_names: train.target_names.clone(),
                    terrain_max_slope_deg: None,
                },
                train,
                test,
                motion_model: None,
                dead_reckoning: Vec::new(),
                test_logs: Vec::new(),
                model: None,
            })
        }
    }
}

pub(crate) fn reference_statistics(
    config: &ExperimentConfig,
    base: &Path,
) -> Option<(String, ResidualStatistics)> {
    let reference = config.compare_with.as_ref()?;
    let path = resolve(base, &reference.path);
    let spec = TableSpec {
        inputs: None,
        targets: reference.targets.clone(),
    };
    match read_residual_table(&path, &spec) {
        Ok(table) => Some((
            reference.path.display().to_string(),
            residual_statistics(&table),
        )),
        Err(e) => {
            tracing::warn!("reference table not used: {e}");
            None
        }
    }
}

/// The rows the regressors see: inputs standardised with the training
/// statistics, targets in physical units.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelRows {
    /// Training rows.
    pub train: ResidualDataset,
    /// Test rows.
    pub test: ResidualDataset,
}

pub(crate) fn model_rows(data: &PreparedData) -> Result<(ModelRows, Standardizer), PipelineError> {
    if data.train.input_names != data.test.input_names
        || data.train.target_names != data.test.target_names
    {
        return Err(PipelineError::Inconsistent(format!(
            "training columns {:?} → {:?}, test columns {:?} → {:?}",
            data.train.input_names,
            data.train.target_names,
            data.test.input_names,
            data.test.target_names
        )));
    }
    let scaler = Standardizer::fit(&data.train.inputs)?;
    let mut train = data.train.clone();
    train.inputs = scaler.transform(&data.train.inputs)?;
    let mut test = data.test.clone();
    test.inputs = scaler.transform(&data.test.inputs)?;
    Ok((ModelRows { train, test }, scaler))
}

/// The data of `config` as the regressors see them, and where they came
/// from (for benchmarks that time the regressors alone).
///
/// # Errors
/// [`PipelineError`] saying which stage failed.
pub fn prepare_model_rows(
    config: &ExperimentConfig,
    base: &Path,
) -> Result<(ModelRows, DatasetSummary), PipelineError> {
    let data = prepare(config, base)?;
    Ok((model_rows(&data)?.0, data.summary))
}

/// Fits one regressor on the training rows and scores it on the test rows.
pub(crate) fn fit_and_score(
    spec: &gpodo_regressors::RegressorSpec,
    train: &ResidualDataset,
    test: &ResidualDataset,
    progress: Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
) -> Result<(RegressorResult, Box<dyn ResidualRegressor>), PipelineError> {
    let label = spec.label();
    tracing::info!(regressor = %label, n = train.len(), "fitting");
    let mut model = spec.build()?;
    model.set_progress(progress);
    let wrap = |source| PipelineError::Regressor {
        label: label.clone(),
        source,
    };
    let fit = model.fit(train).map_err(wrap)?;
    let predictions = model.predict(&test.inputs).map_err(wrap)?;
    let evaluation = evaluate(&predictions, &test.targets)?;
    tracing::info!(regressor = %label, secs = fit.duration_secs, "fitted");
    Ok((
        RegressorResult {
            label,
            spec: spec.clone(),
            fit,
            evaluation,
        },
        model,
    ))
}

/// Runs `config`; relative paths are resolved against `base` (the
/// experiment file's folder).
///
/// # Errors
/// [`PipelineError`] saying which stage failed.
pub fn run_experiment(
    config: &ExperimentConfig,
    base: &Path,
) -> Result<ExperimentResults, PipelineError> {
    let start = Instant::now();
    let shared = SharedWork::build(&[(config, base)], None)?;
    let mut results = shared.results(config, base)?;
    results.duration_secs = start.elapsed().as_secs_f64();
    Ok(results)
}
