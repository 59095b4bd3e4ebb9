//! Per sample: the rover's motion model, the saved regressor's prediction
//! on the row in force, the twist and its covariance, and the pose.
//!
//! In gpodo's mode the twist is the motion model's plus the predicted
//! residual, with the predictive variance as its linear covariance; in the
//! authors' mode (a model of |residual|, `slam-orogen-gp_odometry`) the
//! twist is left as the motion model gives it and the linear variance is
//! the prediction squared. The regressor says nothing of rotation: the
//! angular variance is a setting. No variance is ever below the floor
//! setting (robot_localization treats a variance under 1e-9 as exact).

use std::path::Path;

use gpodo_datasets::residuals::{sample_feature_names, sample_features};
use gpodo_kinematics::RoverDescription;
use gpodo_kinematics::spec::{AttitudeWithoutImu, MotionModelSpec};
use gpodo_regressors::model_file::{ModelFile, Predictor, SavedState};
use gpodo_traits::{BodyTwist, MotionModel, ProprioceptiveSample, SampleMatrix};
use nalgebra::{Isometry3, Matrix6, Vector3};

use crate::NodeError;
use crate::covariance::{propagate, row_major};
use crate::rows::LiveRows;

/// What the twist and its covariance are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OdometryMode {
    /// The motion model's twist plus the predicted residual; the
    /// predictive variance.
    Corrected,
    /// The motion model's twist; the predicted |residual| squared (the
    /// authors' on-board odometry).
    Authors,
}

/// Settings of the live pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveSettings {
    /// No variance published is below this ((m/s)² or (rad/s)²; default
    /// 1e-8).
    pub min_variance: f64,
    /// The angular velocity's variance ((rad/s)²; default 1e-4, i.e.
    /// 0.01 rad/s): the regressor predicts linear residuals only.
    pub angular_variance: f64,
    /// An input is outside the training range when its value, z-scored
    /// by the training rows, exceeds this in magnitude (default 4).
    pub out_of_range_z: f64,
    /// The IMU is stale when the reading a joint state gets is older than
    /// this (s; default 0.5).
    pub stale_imu_secs: f64,
}

impl Default for LiveSettings {
    fn default() -> Self {
        Self {
            min_variance: 1e-8,
            angular_variance: 1e-4,
            out_of_range_z: 4.0,
            stale_imu_secs: 0.5,
        }
    }
}

/// What one sample produced.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveOutput {
    /// The sample's time (s).
    pub time_secs: f64,
    /// The row the prediction used, in [`LiveModel::columns`]' order
    /// (none before the first window has a step: the twist is then the
    /// motion model's, its variance the angular setting's).
    pub row: Option<Vec<f64>>,
    /// Seconds of steps the row averages.
    pub covered_secs: f64,
    /// The sample's own inputs, in [`LiveModel::columns`]' order.
    pub inputs: Vec<f64>,
    /// The motion model's twist.
    pub uncorrected: BodyTwist,
    /// The twist published.
    pub twist: BodyTwist,
    /// Variances of the published twist: linear x, y, z, then angular.
    pub variance: [f64; 6],
    /// `odom_from_body`, integrated from the published twists.
    pub pose: Isometry3<f64>,
    /// The pose's covariance (row-major: x, y, z, then rotation about the
    /// odom frame's x, y, z), propagated from the twists' (see
    /// [`crate::covariance`]); no diagonal element below the floor.
    pub pose_covariance: [f64; 36],
    /// The same integrated from the motion model's twists alone.
    pub uncorrected_pose: Isometry3<f64>,
    /// The model's inputs whose value in the row is outside the training
    /// range (see [`LiveSettings::out_of_range_z`]).
    pub out_of_range: Vec<String>,
    /// The residual's predicted mean and variance on the row, before the
    /// variance floor (none without a row).
    pub residual: Option<([f64; 3], [f64; 3])>,
}

/// A residual predicted on the node's rows by something other than the
/// saved model: the online learner, whose predictions replace the saved
/// model's once it runs.
pub trait RowResidual {
    /// The residual's mean and variance on `row` (in
    /// [`LiveModel::columns`]' order).
    ///
    /// # Errors
    /// Why there is no prediction.
    fn residual(&self, row: &[f64]) -> Result<([f64; 3], [f64; 3]), String>;
}

/// What a model is, for the node's diagnostics.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelSummary {
    /// Its kind (`exact_gp`, `sparse_gp`, `ilgr`, `sparse_spectrum`).
    pub kind: String,
    /// Its label: the kind with its kernel and settings.
    pub label: String,
    /// Rows it was trained on.
    pub training_rows: usize,
}

/// A saved model run live on one robot.
pub struct LiveModel {
    summary: ModelSummary,
    predictor: Predictor,
    columns: Vec<String>,
    /// Per model input with a training z-scoring: its column in the row,
    /// its training mean and standard deviation.
    ranges: Vec<(usize, f64, f64)>,
    motion: Box<dyn MotionModel>,
    wheel_radius_m: f64,
    mode: OdometryMode,
    settings: LiveSettings,
    rows: LiveRows,
    /// The previous sample's time, published and uncorrected twists, and
    /// the published twist's variances.
    last: Option<(f64, BodyTwist, BodyTwist, [f64; 6])>,
    pose: Isometry3<f64>,
    pose_covariance: Matrix6<f64>,
    uncorrected_pose: Isometry3<f64>,
}

impl LiveModel {
    /// Loads `model_path` for the rover described at `rover_path`, whose
    /// streams give an IMU or not and the robot's own odometry or not.
    ///
    /// # Errors
    /// [`NodeError::Model`] for a file that cannot be read, that does not
    /// say how its rows were made, or whose windowing or motion model
    /// cannot be reproduced; [`NodeError::MissingColumns`] when it reads
    /// columns this robot does not give.
    pub fn load(
        model_path: &Path,
        rover_path: &Path,
        imu: bool,
        odometry: bool,
        settings: LiveSettings,
    ) -> Result<Self, NodeError> {
        let model_error = |detail: String| NodeError::Model {
            path: model_path.to_path_buf(),
            detail,
        };
        let file = ModelFile::load(model_path).map_err(|e| model_error(e.to_string()))?;
        let recipe = file.rows.clone().ok_or_else(|| {
            model_error(
                "the file does not say how its input rows were made (a model of version 2 or older, or one fitted on a residual table); fit it again with `gpodo fit` from logs, bags or the simulator".into(),
            )
        })?;
        if recipe
            .window_secs
            .is_some_and(|w| !(w.is_finite() && w > 0.0))
        {
            return Err(model_error(format!(
                "its rows average {:?} s, which no live window can reproduce",
                recipe.window_secs
            )));
        }
        let spec: MotionModelSpec = serde_json::from_value(recipe.motion_model.clone())
            .map_err(|e| model_error(format!("its motion model cannot be read: {e}")))?;
        if !imu
            && matches!(
                spec,
                MotionModelSpec::WeightedJacobian {
                    attitude_without_imu: AttitudeWithoutImu::GroundTruth,
                    ..
                }
            )
        {
            return Err(model_error(
                "its motion model took roll and pitch from the ground truth (`attitude_without_imu: ground_truth`), which a robot without an IMU does not have live".into(),
            ));
        }
        let spec = spec.with_rover(rover_path.to_path_buf());
        let (motion, rover) = spec.build().map_err(|e| {
            model_error(format!("its motion model on {}: {e}", rover_path.display()))
        })?;
        let rover = match rover {
            Some(r) => r,
            None => RoverDescription::from_path(rover_path)
                .map_err(|e| model_error(format!("{}: {e}", rover_path.display())))?,
        };
        let columns = sample_feature_names(
            &rover.wheel_names(),
            &rover.steer_names(),
            &rover.bogie_names(),
            imu,
            odometry,
        );
        let missing: Vec<String> = file
            .input_names
            .iter()
            .filter(|n| !columns.contains(n))
            .cloned()
            .collect();
        if !missing.is_empty() {
            return Err(NodeError::MissingColumns {
                path: model_path.to_path_buf(),
                missing,
                given: columns,
            });
        }
        let ranges = match &file.input_standardizer {
            Some(z) => file
                .input_names
                .iter()
                .zip(z.mean.iter().zip(&z.std))
                .filter_map(|(name, (&m, &s))| {
                    Some((columns.iter().position(|c| c == name)?, m, s))
                })
                .collect(),
            None => Vec::new(),
        };
        let predictor = file.predictor().map_err(|e| model_error(e.to_string()))?;
        let kind = match &file.state {
            SavedState::ExactGp(_) => "exact_gp",
            SavedState::SparseGp(_) => "sparse_gp",
            SavedState::Ilgr(_) => "ilgr",
            SavedState::SparseSpectrum(_) => "sparse_spectrum",
            SavedState::StreamingSparseGp(_) => "streaming_sparse_gp",
        };
        Ok(Self {
            summary: ModelSummary {
                kind: kind.into(),
                label: file.label.clone(),
                training_rows: file.provenance.training_rows,
            },
            predictor,
            columns,
            ranges,
            motion,
            wheel_radius_m: rover.wheel_radius_m,
            mode: if recipe.absolute_targets {
                OdometryMode::Authors
            } else {
                OdometryMode::Corrected
            },
            settings,
            rows: LiveRows::new(recipe.window_secs),
            last: None,
            pose: Isometry3::identity(),
            pose_covariance: Matrix6::zeros(),
            uncorrected_pose: Isometry3::identity(),
        })
    }

    /// What the model is.
    pub fn summary(&self) -> &ModelSummary {
        &self.summary
    }

    /// The settings it runs with.
    pub fn settings(&self) -> &LiveSettings {
        &self.settings
    }

    /// The columns of the rows this robot gives, in order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The window the rows average (s; none: one row per sample).
    pub fn window_secs(&self) -> Option<f64> {
        self.rows.window_secs()
    }

    /// Gpodo's mode or the authors'.
    pub fn mode(&self) -> OdometryMode {
        self.mode
    }

    /// Processes one sample (joints in the rover's order; the IMU's latest
    /// reading, if the robot has one).
    ///
    /// # Errors
    /// [`NodeError::Sample`] for a sample that does not fit the rover, a
    /// time that does not move forward, a non-finite input, or a model
    /// that fails on it; the pipeline is left as it was.
    pub fn process(&mut self, sample: &ProprioceptiveSample) -> Result<LiveOutput, NodeError> {
        self.process_with(sample, None)
    }

    /// [`LiveModel::process`] with the residual predicted by `residual`
    /// instead of the saved model, when given (gpodo's mode only: the
    /// authors' odometry reads a model of |residual|).
    ///
    /// # Errors
    /// As [`LiveModel::process`]; a `residual` in the authors' mode.
    pub fn process_with(
        &mut self,
        sample: &ProprioceptiveSample,
        residual: Option<&dyn RowResidual>,
    ) -> Result<LiveOutput, NodeError> {
        let time_secs = sample.time_secs;
        let bad = |detail: String| NodeError::Sample { time_secs, detail };
        let inputs = sample_features(sample, self.wheel_radius_m);
        if inputs.len() != self.columns.len() {
            return Err(bad(format!(
                "{} inputs, this robot's rows have {} ({:?})",
                inputs.len(),
                self.columns.len(),
                self.columns
            )));
        }
        if let Some(k) = inputs.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!("`{}` is not finite", self.columns[k])));
        }
        let dt = self.last.map(|(t, _, _, _)| time_secs - t);
        if dt.is_some_and(|dt| dt <= 0.0) {
            return Err(bad("its time is not after the previous sample's".into()));
        }
        let estimate = self
            .motion
            .estimate(sample, dt.unwrap_or(0.0))
            .map_err(|e| bad(format!("the motion model: {e}")))?;
        // The row is committed only once the sample has gone through.
        let row = self.rows.peek(time_secs, &inputs)?;
        let floor = self.settings.min_variance;
        let angular = self.settings.angular_variance.max(floor);
        let uncorrected = estimate.twist;
        if residual.is_some() && self.mode == OdometryMode::Authors {
            return Err(bad(
                "a residual from elsewhere than the saved model, which predicts |residual| (the authors' mode)".into(),
            ));
        }
        let predicted = match (&row, residual) {
            (None, _) => None,
            (Some(row), Some(r)) => Some(
                r.residual(&row.inputs)
                    .map_err(|e| bad(format!("the residual: {e}")))?,
            ),
            (Some(row), None) => {
                let x = SampleMatrix::from_rows(row.inputs.len(), &[&row.inputs])
                    .map_err(|e| bad(e.to_string()))?;
                let p = self
                    .predictor
                    .predict(&self.columns, &x)
                    .map_err(|e| bad(format!("the model: {e}")))?;
                let (mean, variance) = (p.mean.row(0), p.variance.row(0));
                if mean.len() < 3 || variance.len() < 3 {
                    return Err(bad(format!(
                        "the model predicted {mean:?} ± {variance:?}; expected three residuals"
                    )));
                }
                Some((
                    [mean[0], mean[1], mean[2]],
                    [variance[0], variance[1], variance[2]],
                ))
            }
        };
        if let Some((mean, variance)) = &predicted
            && mean.iter().chain(variance).any(|v| !v.is_finite())
        {
            return Err(bad(format!(
                "the residual predicted is {mean:?} ± {variance:?}; expected finite values"
            )));
        }
        let (twist, linear) = match &predicted {
            None => (uncorrected, [angular; 3]),
            Some((mean, variance)) => match self.mode {
                OdometryMode::Corrected => (
                    BodyTwist {
                        linear_mps: uncorrected.linear_mps
                            + Vector3::new(mean[0], mean[1], mean[2]),
                        angular_radps: uncorrected.angular_radps,
                    },
                    [variance[0], variance[1], variance[2]],
                ),
                OdometryMode::Authors => (
                    uncorrected,
                    [mean[0] * mean[0], mean[1] * mean[1], mean[2] * mean[2]],
                ),
            },
        };
        self.rows.commit(time_secs, inputs.clone());
        if let (Some(dt), Some((_, previous, wheels, previous_variance))) = (dt, self.last) {
            self.pose_covariance = propagate(
                &self.pose_covariance,
                &self.pose,
                &previous.linear_mps,
                &previous.angular_radps,
                &previous_variance,
                dt,
            );
            self.pose *= previous.pose_delta(dt);
            self.uncorrected_pose *= wheels.pose_delta(dt);
        }
        let variance = [
            linear[0].max(floor),
            linear[1].max(floor),
            linear[2].max(floor),
            angular,
            angular,
            angular,
        ];
        self.last = Some((time_secs, twist, uncorrected, variance));
        let out_of_range = row.as_ref().map_or_else(Vec::new, |r| {
            self.ranges
                .iter()
                .filter(|(c, m, s)| ((r.inputs[*c] - m) / s).abs() > self.settings.out_of_range_z)
                .map(|(c, _, _)| self.columns[*c].clone())
                .collect()
        });
        Ok(LiveOutput {
            out_of_range,
            time_secs,
            covered_secs: row.as_ref().map_or(0.0, |r| r.covered_secs),
            row: row.map(|r| r.inputs),
            inputs,
            uncorrected,
            twist,
            variance,
            pose: self.pose,
            pose_covariance: row_major(&self.pose_covariance, floor),
            uncorrected_pose: self.uncorrected_pose,
            residual: predicted,
        })
    }
}
