//! What a run produced: the data summary, each regressor's scores, each
//! scheme's row, and the rows and traverses the reports draw.

use gpodo_datasets::residuals::StepWindows;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::scheme::SchemeResult;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::stereo::StereoFrames;
use gpodo_regressors::metrics::{Evaluation, evaluate};
use gpodo_traits::{FitReport, Predictions, ResidualDataset};
use serde::{Deserialize, Serialize};

use crate::config::ExperimentConfig;
use crate::error::PipelineError;
use crate::execute::calibration::ResidualStatistics;
use crate::execute::odometry::DeadReckoning;

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
    /// Where the motion model's roll and pitch came from.
    #[serde(default)]
    pub attitude: Attitude,
    /// Without an IMU, where the motion model's yaw rate came from.
    #[serde(default)]
    pub yaw_rate_without_imu: Option<String>,
    /// The unit check: the median ratio of the motion model's speed to the
    /// ground truth's over the training runs' moving seconds (`None` for a
    /// residual table, or runs that never move).
    #[serde(default)]
    pub speed_ratio: Option<f64>,
}

/// Where the motion model's roll and pitch came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Attitude {
    /// The IMU (or the data have no runs: a residual table).
    #[default]
    Imu,
    /// No IMU: level ground.
    Level,
    /// No IMU: the ground truth's, opted in.
    GroundTruth,
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
    /// One entry per |residual| regressor (`absolute_regressors`), scored
    /// against |residual| on the test rows.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub absolute_regressors: Vec<RegressorResult>,
    /// Table II: every scheme on every test run.
    #[serde(default)]
    pub schemes: Vec<SchemeResult>,
    /// Wall-clock duration of the whole experiment (s).
    pub duration_secs: f64,
    /// CPU time the process had used when the run was recorded, on all
    /// threads (s; for a single run, the run's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_secs: Option<f64>,
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
    /// Each traverse's camera frames, for runs whose VO reads images (for
    /// the figures of the frames around each loss of track).
    #[serde(skip)]
    pub camera_frames: CameraFrames,
}

/// Each test traverse's camera frames and their cached features (`None`
/// for a traverse without images). A cache of what the traverses
/// determine, so results compare equal whatever it holds.
#[derive(Clone, Default)]
pub struct CameraFrames(pub Vec<Option<std::sync::Arc<StereoFrames>>>);

impl CameraFrames {
    /// The frames of traverse `t`, if it has images.
    pub fn of(&self, t: usize) -> Option<&StereoFrames> {
        self.0.get(t)?.as_deref()
    }
}

impl std::fmt::Debug for CameraFrames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let with = self.0.iter().filter(|c| c.is_some()).count();
        write!(f, "CameraFrames({with} of {} traverses)", self.0.len())
    }
}

impl PartialEq for CameraFrames {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The rows the regressors see: inputs standardised once, here, with the
/// training statistics (and marked so, so no regressor z-scores them
/// again), targets in physical units.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelRows {
    /// Training rows.
    pub train: ResidualDataset,
    /// Test rows: what the regressors predict.
    pub test: ResidualDataset,
    /// The windows the test rows' predictions are averaged over and scored
    /// on (`residuals.score_window_secs` with one row per step); `None`:
    /// scored row by row.
    pub test_windows: Option<StepWindows>,
}

impl ModelRows {
    /// Scores predictions of the test rows: on the scoring windows when
    /// there are some, else row by row.
    ///
    /// # Errors
    /// [`PipelineError`] when the predictions do not match the test rows.
    pub fn score(&self, predictions: &Predictions) -> Result<Evaluation, PipelineError> {
        Ok(match &self.test_windows {
            Some(windows) => evaluate(&windows.average(predictions)?, &windows.targets)?,
            None => evaluate(predictions, &self.test.targets)?,
        })
    }
}
