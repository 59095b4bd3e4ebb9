//! The residual dataset of the paper's §IV-C, built from rover logs and a
//! motion model.
//!
//! For each step `k` of a log, with `dt = t(k+1) − t(k)`:
//!
//! * target `y_k = s(k+1) − s(k) − g(s(k), u̇(k))`, expressed as a body-frame
//!   velocity: the ground-truth displacement over the step in the body frame
//!   at `k`, divided by `dt`, minus the motion model's body velocity
//!   (outputs `res_vx, res_vy, res_vz`, m/s);
//! * inputs `x_k`: the paper's list (§V), named as in the authors' ExoTeR
//!   table: `roll, pitch`, bogie and steering positions (`pos_*_passive`,
//!   `pos_*_steer`), their speeds (`spd_*`), the wheels' translational speeds
//!   (`spd_*_transl` = radius × wheel rate), `acc_x..z`, `gyro_x..z`;
//!   when the log carries the robot's own odometry, its twist too
//!   (`odom_vx..vz`, `odom_wx..wz`): for a robot without joint encoders it
//!   is what plays the joint speeds' part.
//!
//! Steps can be averaged over windows (the authors used 1-s means; they
//! also low-pass the motion-capture velocities, which the window does
//! here). Inputs are left in physical units: normalisation uses training
//! statistics only, see [`gpodo_traits::Standardizer`].

use gpodo_traits::{MotionModel, Predictions, ProprioceptiveSample, ResidualDataset, SampleMatrix};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::DatasetError;
use crate::log::RoverLog;

/// Names of the three targets.
pub const TARGET_NAMES: [&str; 3] = ["res_vx", "res_vy", "res_vz"];

/// How steps become rows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ResidualConfig {
    /// Average inputs and targets over consecutive windows of this length
    /// (s); `None` keeps one row per step. Default: 1 s, as the authors.
    pub window_secs: Option<f64>,
    /// Take absolute values of the (averaged) targets, as in the authors'
    /// ExoTeR table. Default: false (signed residuals).
    pub absolute_targets: bool,
    /// Score the regressors on the test runs' windows of this length (s)
    /// when they train on one row per step (`window_secs: null`): their
    /// per-step predictions are averaged over each window with the window's
    /// own weights ([`window_rows`]), so that models trained on steps and on
    /// windows are scored on the same held-out rows. `None` (default): the
    /// test rows are made as the training rows are.
    pub score_window_secs: Option<f64>,
}

impl Default for ResidualConfig {
    fn default() -> Self {
        Self {
            window_secs: Some(1.0),
            absolute_targets: false,
            score_window_secs: None,
        }
    }
}

impl ResidualConfig {
    /// Checks every field.
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), DatasetError> {
        let bad = |field: &str, expected: &str| {
            Err(DatasetError::InvalidConfig {
                field: format!("residuals.{field}"),
                expected: expected.into(),
            })
        };
        if let Some(s) = self.score_window_secs {
            if !(s.is_finite() && s > 0.0) {
                return bad("score_window_secs", "a positive number of seconds, or null");
            }
            if self.window_secs.is_some_and(|w| w != s) {
                return bad(
                    "score_window_secs",
                    "the same length as `window_secs`, or `window_secs: null` (one training row per step)",
                );
            }
            if self.absolute_targets {
                return bad(
                    "score_window_secs",
                    "no scoring windows with `absolute_targets` (the mean of absolute step residuals is not the absolute window mean)",
                );
            }
        }
        match self.window_secs {
            Some(w) if !(w.is_finite() && w > 0.0) => bad(
                "window_secs",
                "a positive number of seconds, or null for one row per step",
            ),
            _ => Ok(()),
        }
    }
}

/// The input column names for a log's joints, in the order the rows hold
/// them.
pub fn feature_names(log: &RoverLog) -> Vec<String> {
    sample_feature_names(
        &log.wheel_names,
        &log.steer_names,
        &log.bogie_names,
        log.samples.first().is_some_and(|s| s.imu.is_some()),
        log.samples.first().is_some_and(|s| s.odometry.is_some()),
    )
}

/// The names of [`sample_features`]' inputs for a rover with these joints
/// (in its order), with or without an IMU and the robot's own odometry.
pub fn sample_feature_names(
    wheels: &[String],
    steers: &[String],
    bogies: &[String],
    imu: bool,
    odometry: bool,
) -> Vec<String> {
    let mut names = Vec::new();
    if imu {
        names.extend(["roll", "pitch"].map(String::from));
    }
    names.extend(bogies.iter().map(|b| format!("pos_{b}_passive")));
    names.extend(steers.iter().map(|s| format!("pos_{s}_steer")));
    names.extend(bogies.iter().map(|b| format!("spd_{b}_passive")));
    names.extend(steers.iter().map(|s| format!("spd_{s}_steer")));
    names.extend(wheels.iter().map(|w| format!("spd_{w}_transl")));
    if imu {
        names.extend(["acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"].map(String::from));
    }
    if odometry {
        names.extend(ODOMETRY_FEATURES.map(String::from));
    }
    names
}

/// Input names of the robot's own odometry twist, when the log has it.
pub const ODOMETRY_FEATURES: [&str; 6] = [
    "odom_vx", "odom_vy", "odom_vz", "odom_wx", "odom_wy", "odom_wz",
];

/// The inputs of step `k`.
fn step_features(log: &RoverLog, k: usize, wheel_radius_m: f64) -> Vec<f64> {
    sample_features(&log.samples[k], wheel_radius_m)
}

/// The inputs one sample gives, in [`feature_names`]' order (its joints in
/// the rover's order; `wheel_radius_m` turns wheel rates into speeds).
pub fn sample_features(s: &ProprioceptiveSample, wheel_radius_m: f64) -> Vec<f64> {
    let mut x = Vec::new();
    if let Some(imu) = &s.imu {
        x.extend([imu.roll_rad, imu.pitch_rad]);
    }
    x.extend(s.bogies.iter().map(|j| j.position_rad));
    x.extend(s.steering.iter().map(|j| j.position_rad));
    x.extend(s.bogies.iter().map(|j| j.rate_radps));
    x.extend(s.steering.iter().map(|j| j.rate_radps));
    x.extend(s.wheels.iter().map(|j| j.rate_radps * wheel_radius_m));
    if let Some(imu) = &s.imu {
        x.extend(imu.accel_mps2.iter().chain(imu.gyro_radps.iter()));
    }
    if let Some(odometry) = &s.odometry {
        x.extend(
            odometry
                .linear_mps
                .iter()
                .chain(odometry.angular_radps.iter()),
        );
    }
    x
}

/// Ground-truth body velocity over step `k`: displacement in the body frame
/// at `k` divided by the step's duration.
pub fn true_body_velocity(log: &RoverLog, k: usize) -> Vector3<f64> {
    let dt = log.samples[k + 1].time_secs - log.samples[k].time_secs;
    let (a, b) = (&log.ground_truth[k], &log.ground_truth[k + 1]);
    a.rotation.inverse() * (b.translation.vector - a.translation.vector) / dt
}

/// One step of a log: its time, duration, inputs, the motion model's body
/// twist and the residual against ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct LogStep {
    /// Time of the step's first sample (s).
    pub time_secs: f64,
    /// Duration of the step (s).
    pub dt_secs: f64,
    /// The inputs `x_k`, in [`feature_names`] order, physical units.
    pub inputs: Vec<f64>,
    /// The motion model's body twist over the step (`g` of eq. 11).
    pub twist: gpodo_traits::BodyTwist,
    /// The residual `y_k` as a body-frame velocity (m/s).
    pub residual: Vector3<f64>,
}

/// Every step of a log (`samples − 1` of them): inputs, model twist and
/// residual.
///
/// # Errors
/// [`DatasetError::Model`] when the motion model fails on a sample.
pub fn log_steps(
    log: &RoverLog,
    model: &dyn MotionModel,
    wheel_radius_m: f64,
) -> Result<Vec<LogStep>, DatasetError> {
    let n = log.samples.len();
    let mut rows = Vec::with_capacity(n.saturating_sub(1));
    for k in 0..n.saturating_sub(1) {
        let dt = log.samples[k + 1].time_secs - log.samples[k].time_secs;
        let estimate = model.estimate(&log.samples[k], dt)?;
        let residual = true_body_velocity(log, k) - estimate.twist.linear_mps;
        rows.push(LogStep {
            time_secs: log.samples[k].time_secs,
            dt_secs: dt,
            inputs: step_features(log, k, wheel_radius_m),
            twist: estimate.twist,
            residual,
        });
    }
    Ok(rows)
}

/// One window of consecutive steps (§IV-C: the authors' 1-s means).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowRow {
    /// Start of the window (s): `t₀ + i · window`, `t₀` the log's first time.
    pub start_secs: f64,
    /// End of the window (s).
    pub end_secs: f64,
    /// The steps it averages (indices into the steps of the log).
    pub steps: std::ops::Range<usize>,
    /// Duration-weighted mean inputs.
    pub inputs: Vec<f64>,
    /// Duration-weighted mean residual (m/s).
    pub residual: Vector3<f64>,
}

/// Averages consecutive steps over windows of `window_secs`, each step
/// weighted by its duration (so the target is the window's mean velocity
/// residual even when samples were dropped); a window whose steps cover less
/// than half its length (a gap in the log, the end of a run) is dropped.
pub fn window_rows(rows: &[LogStep], window_secs: f64) -> Vec<WindowRow> {
    let Some(t0) = rows.first().map(|r| r.time_secs) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut start = 0;
    while start < rows.len() {
        let window = ((rows[start].time_secs - t0) / window_secs).floor();
        let end = rows[start..]
            .iter()
            .position(|r| ((r.time_secs - t0) / window_secs).floor() != window)
            .map_or(rows.len(), |n| start + n);
        let group = &rows[start..end];
        let covered: f64 = group.iter().map(|r| r.dt_secs).sum();
        if covered >= 0.5 * window_secs {
            let mut x = vec![0.0; group[0].inputs.len()];
            let mut y = Vector3::zeros();
            for r in group {
                let w = r.dt_secs / covered;
                for (acc, v) in x.iter_mut().zip(&r.inputs) {
                    *acc += w * v;
                }
                y += r.residual * w;
            }
            out.push(WindowRow {
                start_secs: t0 + window * window_secs,
                end_secs: t0 + (window + 1.0) * window_secs,
                steps: start..end,
                inputs: x,
                residual: y,
            });
        }
        start = end;
    }
    out
}

/// Windows over one-row-per-step residuals, to score per-step predictions
/// on window targets ([`ResidualConfig::score_window_secs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StepWindows {
    /// Each window's duration-weighted mean residual (m/s), `windows × 3`.
    pub targets: SampleMatrix,
    /// Each window's steps: the step's row in the logs' steps concatenated
    /// in order (the rows of a `window_secs: null` dataset) and its weight
    /// (its duration over the window's covered time; they sum to 1).
    pub members: Vec<Vec<(usize, f64)>>,
}

impl StepWindows {
    /// The windows of `window_secs` over each log's steps ([`window_rows`],
    /// so the same windows, with the same targets, as a dataset made with
    /// `window_secs`), indexing the steps of all logs concatenated.
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] for a window that is not a positive
    /// number of seconds.
    pub fn new(steps: &[Vec<LogStep>], window_secs: f64) -> Result<Self, DatasetError> {
        if !(window_secs.is_finite() && window_secs > 0.0) {
            return Err(DatasetError::InvalidConfig {
                field: "residuals.score_window_secs".into(),
                expected: "a positive number of seconds".into(),
            });
        }
        let mut targets = Vec::new();
        let mut members = Vec::new();
        let mut offset = 0;
        for rows in steps {
            for w in window_rows(rows, window_secs) {
                let covered: f64 = rows[w.steps.clone()].iter().map(|r| r.dt_secs).sum();
                members.push(
                    w.steps
                        .clone()
                        .map(|k| (offset + k, rows[k].dt_secs / covered))
                        .collect(),
                );
                targets.extend(w.residual.iter());
            }
            offset += rows.len();
        }
        let n = members.len();
        Ok(Self {
            targets: SampleMatrix::from_row_major(n, 3, targets)?,
            members,
        })
    }

    /// Per-step predictions averaged over each window with its weights: the
    /// mean of the window's mean, and, for the variance, the steps' errors
    /// taken as independent (`Σ wᵢ² σᵢ²`).
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] when the predictions have fewer rows
    /// than the windows index.
    pub fn average(&self, predictions: &Predictions) -> Result<Predictions, DatasetError> {
        let (rows, p) = (predictions.mean.nrows(), predictions.mean.ncols());
        let needed = self
            .members
            .iter()
            .flat_map(|m| m.iter().map(|&(k, _)| k + 1))
            .max()
            .unwrap_or(0);
        if rows < needed || predictions.variance.nrows() != rows {
            return Err(DatasetError::InvalidConfig {
                field: "predictions".into(),
                expected: format!(
                    "one row per step ({needed} at least) for the scoring windows, not {rows}"
                ),
            });
        }
        let n = self.members.len();
        let mut mean = vec![0.0; n * p];
        let mut variance = vec![0.0; n * p];
        for (i, m) in self.members.iter().enumerate() {
            for &(k, w) in m {
                let (mu, var) = (predictions.mean.row(k), predictions.variance.row(k));
                for j in 0..p {
                    mean[i * p + j] += w * mu[j];
                    variance[i * p + j] += w * w * var[j];
                }
            }
        }
        Ok(Predictions {
            mean: SampleMatrix::from_row_major(n, p, mean)?,
            variance: SampleMatrix::from_row_major(n, p, variance)?,
        })
    }
}

/// Builds the residual dataset of several logs (rows concatenated in order).
///
/// # Errors
/// [`DatasetError::InvalidConfig`] for a bad config or logs of different
/// rovers, [`DatasetError::Model`] when the motion model fails on a sample.
pub fn residual_dataset(
    logs: &[&RoverLog],
    model: &dyn MotionModel,
    wheel_radius_m: f64,
    config: &ResidualConfig,
) -> Result<ResidualDataset, DatasetError> {
    config.validate()?;
    let steps = logs
        .iter()
        .map(|log| {
            log.validate()?;
            log_steps(log, model, wheel_radius_m)
        })
        .collect::<Result<Vec<_>, _>>()?;
    residual_dataset_from_steps(logs, &steps, config)
}

/// [`residual_dataset`] from the logs' steps already computed
/// ([`log_steps`], one entry per log, in the same order), so that a caller
/// that also needs the steps runs the motion model once.
///
/// # Errors
/// As [`residual_dataset`], but for the motion model's.
pub fn residual_dataset_from_steps(
    logs: &[&RoverLog],
    steps: &[Vec<LogStep>],
    config: &ResidualConfig,
) -> Result<ResidualDataset, DatasetError> {
    config.validate()?;
    let Some(first) = logs.first() else {
        return Err(DatasetError::InvalidConfig {
            field: "runs".into(),
            expected: "at least one run".into(),
        });
    };
    let names = feature_names(first);
    let mut inputs = Vec::new();
    let mut targets = Vec::new();
    for (log, rows) in logs.iter().zip(steps) {
        if feature_names(log) != names {
            return Err(DatasetError::InvalidConfig {
                field: format!("runs ({})", log.name),
                expected: format!("the same inputs (joints, odometry) as run {}", first.name),
            });
        }
        match config.window_secs {
            Some(w) => {
                for r in window_rows(rows, w) {
                    push_row(&mut inputs, &mut targets, &r.inputs, r.residual, config);
                }
            }
            None => {
                for r in rows {
                    push_row(&mut inputs, &mut targets, &r.inputs, r.residual, config);
                }
            }
        }
    }
    let n = targets.len() / 3;
    Ok(ResidualDataset::new(
        SampleMatrix::from_row_major(n, names.len(), inputs)?,
        SampleMatrix::from_row_major(n, 3, targets)?,
        names,
        TARGET_NAMES.iter().map(|s| s.to_string()).collect(),
    )?)
}

/// Appends one row (its target absolute when the config says so).
fn push_row(
    inputs: &mut Vec<f64>,
    targets: &mut Vec<f64>,
    x: &[f64],
    y: Vector3<f64>,
    config: &ResidualConfig,
) {
    inputs.extend_from_slice(x);
    let y = if config.absolute_targets { y.abs() } else { y };
    targets.extend(y.iter());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(times: &[f64]) -> Vec<LogStep> {
        times
            .iter()
            .map(|&t| LogStep {
                time_secs: t,
                dt_secs: 0.25,
                inputs: vec![t],
                twist: Default::default(),
                residual: Vector3::new(t, 2.0 * t, 0.0),
            })
            .collect()
    }

    fn windowed(rows: Vec<LogStep>, window_secs: f64) -> Vec<(Vec<f64>, Vector3<f64>)> {
        window_rows(&rows, window_secs)
            .into_iter()
            .map(|w| (w.inputs, w.residual))
            .collect()
    }

    #[test]
    fn windows_average_consecutive_steps_and_drop_a_short_tail() {
        let times: Vec<f64> = (0..11).map(|k| 0.25 * k as f64).collect(); // 0 … 2.5 s
        let full = window_rows(&rows(&times), 1.0);
        assert_eq!(full[2].steps, 8..11);
        assert_eq!((full[2].start_secs, full[2].end_secs), (2.0, 3.0));
        let out = windowed(rows(&times), 1.0);
        // Windows [0,1), [1,2) are complete; [2,3) holds 2.0, 2.25, 2.5:
        // 0.75 s covered ≥ half a window, kept.
        assert_eq!(out.len(), 3);
        assert!((out[0].0[0] - 0.375).abs() < 1e-15);
        assert!((out[1].1.y - 2.0 * 1.375).abs() < 1e-15);
        let out = windowed(rows(&times[..9]), 1.0); // tail 2.0 only
        assert_eq!(out.len(), 2);
    }

    #[test]
    fn windows_weight_steps_by_their_duration() {
        // A dropped sample: one step lasts 0.5 s, two last 0.25 s.
        let mut r = rows(&[0.0, 0.5, 0.75]);
        r[0].dt_secs = 0.5;
        let out = windowed(r, 1.0);
        assert_eq!(out.len(), 1);
        let expected = 0.5 * 0.0 + 0.25 * 0.5 + 0.25 * 0.75;
        assert!((out[0].1.x - expected).abs() < 1e-15, "{}", out[0].1.x);
    }

    #[test]
    fn scoring_windows_average_step_predictions_into_the_window_targets() {
        // Two logs: the second's indices start after the first's 10 steps;
        // one step of the first lasts 0.5 s (a dropped sample).
        let mut first = rows(&[0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.25, 2.5]);
        first[6].dt_secs = 0.5;
        let second = rows(&[10.0, 10.25, 10.5, 10.75, 11.0, 11.25]);
        let steps = vec![first.clone(), second.clone()];
        let windows = StepWindows::new(&steps, 1.0).unwrap();
        // The same windows and targets as window_rows gives.
        let expected: Vec<WindowRow> = window_rows(&first, 1.0)
            .into_iter()
            .chain(window_rows(&second, 1.0))
            .collect();
        assert_eq!(windows.members.len(), expected.len());
        for (i, w) in expected.iter().enumerate() {
            for j in 0..3 {
                assert_eq!(windows.targets.row(i)[j], w.residual[j]);
            }
        }
        assert_eq!(windows.members[3][0].0, 10, "the second log's first step");
        // Predicting every step's own residual, variance 1: the average is
        // the window target, the variance the sum of squared weights.
        let all: Vec<&LogStep> = first.iter().chain(&second).collect();
        let n = all.len();
        let mean = SampleMatrix::from_row_major(
            n,
            3,
            all.iter()
                .flat_map(|s| s.residual.iter().copied())
                .collect(),
        )
        .unwrap();
        let variance = SampleMatrix::from_row_major(n, 3, vec![1.0; 3 * n]).unwrap();
        let averaged = windows.average(&Predictions { mean, variance }).unwrap();
        for i in 0..expected.len() {
            let squares: f64 = windows.members[i].iter().map(|(_, w)| w * w).sum();
            for j in 0..3 {
                assert!((averaged.mean.row(i)[j] - windows.targets.row(i)[j]).abs() < 1e-15);
                assert!((averaged.variance.row(i)[j] - squares).abs() < 1e-15);
            }
        }
        // Window [1, 2): steps 1.0, 1.25 (0.25 s each) and 1.5 (0.5 s).
        let weights: Vec<f64> = windows.members[1].iter().map(|(_, w)| *w).collect();
        assert_eq!(weights, vec![0.25, 0.25, 0.5]);
        // Fewer predictions than steps is an error, not a panic.
        let short = Predictions {
            mean: SampleMatrix::from_row_major(2, 3, vec![0.0; 6]).unwrap(),
            variance: SampleMatrix::from_row_major(2, 3, vec![1.0; 6]).unwrap(),
        };
        assert!(windows.average(&short).is_err());
    }

    #[test]
    fn scoring_windows_are_checked_against_the_training_rows() {
        let per_step = |score: f64| ResidualConfig {
            window_secs: None,
            score_window_secs: Some(score),
            ..Default::default()
        };
        assert!(per_step(1.0).validate().is_ok());
        let field = |c: ResidualConfig| match c.validate() {
            Err(DatasetError::InvalidConfig { field, .. }) => field,
            other => panic!("{other:?}"),
        };
        assert_eq!(field(per_step(0.0)), "residuals.score_window_secs");
        let other_window = ResidualConfig {
            window_secs: Some(2.0),
            score_window_secs: Some(1.0),
            ..Default::default()
        };
        assert_eq!(field(other_window), "residuals.score_window_secs");
        let absolute = ResidualConfig {
            absolute_targets: true,
            ..per_step(1.0)
        };
        assert_eq!(field(absolute), "residuals.score_window_secs");
        let same = ResidualConfig {
            window_secs: Some(1.0),
            score_window_secs: Some(1.0),
            ..Default::default()
        };
        assert!(same.validate().is_ok());
    }

    /// Reports a constant body velocity.
    struct Constant(Vector3<f64>);

    impl MotionModel for Constant {
        fn name(&self) -> &str {
            "constant"
        }
        fn estimate(
            &self,
            _: &gpodo_traits::ProprioceptiveSample,
            _: f64,
        ) -> Result<gpodo_traits::MotionEstimate, gpodo_traits::Error> {
            Ok(gpodo_traits::MotionEstimate {
                twist: gpodo_traits::BodyTwist {
                    linear_mps: self.0,
                    angular_radps: Vector3::zeros(),
                },
                ..Default::default()
            })
        }
    }

    #[test]
    fn target_is_truth_minus_model_in_the_body_frame_at_the_step_start() {
        use nalgebra::{Isometry3, UnitQuaternion};
        // Heading 90° left: moving +y in the world is moving forward.
        let yaw = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let start = Isometry3::from_parts(Vector3::new(1.0, 2.0, 0.0).into(), yaw);
        let end = Isometry3::from_parts(Vector3::new(1.0, 2.1, 0.0).into(), yaw * yaw);
        let sample = |t: f64| gpodo_traits::ProprioceptiveSample {
            time_secs: t,
            ..Default::default()
        };
        let log = RoverLog {
            name: "two".into(),
            wheel_names: vec![],
            steer_names: vec![],
            bogie_names: vec![],
            samples: vec![sample(0.0), sample(2.0)],
            ground_truth: vec![start, end],
            camera_times_secs: vec![],
        };
        // Truth: 0.1 m forward in 2 s = 0.05 m/s along body x at the start.
        let model = Constant(Vector3::new(0.04, 0.01, 0.0));
        let config = ResidualConfig {
            window_secs: None,
            absolute_targets: false,
            score_window_secs: None,
        };
        let data = residual_dataset(&[&log], &model, 0.07, &config).unwrap();
        let y = data.targets.row(0);
        assert!((y[0] - 0.01).abs() < 1e-15, "{y:?}");
        assert!((y[1] + 0.01).abs() < 1e-15, "{y:?}");
        assert!(y[2].abs() < 1e-15, "{y:?}");
    }

    #[test]
    fn bad_window_is_rejected_with_the_field_name() {
        let c = ResidualConfig {
            window_secs: Some(0.0),
            ..Default::default()
        };
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .contains("window_secs")
        );
    }
}
