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
//!   (`spd_*_transl` = radius × wheel rate), `acc_x..z`, `gyro_x..z`.
//!
//! Steps can be averaged over windows (the authors used 1-s means; they
//! also low-pass the motion-capture velocities, which the window does
//! here). Inputs are left in physical units: normalisation uses training
//! statistics only, see [`crate::standardize`].

use gpodo_traits::{MotionModel, ResidualDataset, SampleMatrix};
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
}

impl Default for ResidualConfig {
    fn default() -> Self {
        Self {
            window_secs: Some(1.0),
            absolute_targets: false,
        }
    }
}

impl ResidualConfig {
    /// Checks every field.
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), DatasetError> {
        match self.window_secs {
            Some(w) if !(w.is_finite() && w > 0.0) => Err(DatasetError::InvalidConfig {
                field: "residuals.window_secs".into(),
                expected: "a positive number of seconds, or null for one row per step".into(),
            }),
            _ => Ok(()),
        }
    }
}

/// The input column names for a log's joints, in the order the rows hold
/// them.
pub fn feature_names(log: &RoverLog) -> Vec<String> {
    let mut names = vec!["roll".to_string(), "pitch".to_string()];
    names.extend(log.bogie_names.iter().map(|b| format!("pos_{b}_passive")));
    names.extend(log.steer_names.iter().map(|s| format!("pos_{s}_steer")));
    names.extend(log.bogie_names.iter().map(|b| format!("spd_{b}_passive")));
    names.extend(log.steer_names.iter().map(|s| format!("spd_{s}_steer")));
    names.extend(log.wheel_names.iter().map(|w| format!("spd_{w}_transl")));
    names.extend(["acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"].map(String::from));
    names
}

/// The inputs of step `k`.
fn step_features(log: &RoverLog, k: usize, wheel_radius_m: f64) -> Vec<f64> {
    let s = &log.samples[k];
    let mut x = vec![s.imu.roll_rad, s.imu.pitch_rad];
    x.extend(s.bogies.iter().map(|j| j.position_rad));
    x.extend(s.steering.iter().map(|j| j.position_rad));
    x.extend(s.bogies.iter().map(|j| j.rate_radps));
    x.extend(s.steering.iter().map(|j| j.rate_radps));
    x.extend(s.wheels.iter().map(|j| j.rate_radps * wheel_radius_m));
    x.extend(s.imu.accel_mps2.iter());
    x.extend(s.imu.gyro_radps.iter());
    x
}

/// Ground-truth body velocity over step `k`: displacement in the body frame
/// at `k` divided by the step's duration.
pub fn true_body_velocity(log: &RoverLog, k: usize) -> Vector3<f64> {
    let dt = log.samples[k + 1].time_secs - log.samples[k].time_secs;
    let (a, b) = (&log.ground_truth[k], &log.ground_truth[k + 1]);
    a.rotation.inverse() * (b.translation.vector - a.translation.vector) / dt
}

/// One step of a log: its time, inputs and residual.
struct StepRow {
    time_secs: f64,
    inputs: Vec<f64>,
    residual: Vector3<f64>,
}

/// Per-step rows of one log.
fn step_rows(
    log: &RoverLog,
    model: &dyn MotionModel,
    wheel_radius_m: f64,
) -> Result<Vec<StepRow>, DatasetError> {
    let n = log.samples.len();
    let mut rows = Vec::with_capacity(n.saturating_sub(1));
    for k in 0..n.saturating_sub(1) {
        let dt = log.samples[k + 1].time_secs - log.samples[k].time_secs;
        let estimate = model.estimate(&log.samples[k], dt)?;
        let residual = true_body_velocity(log, k) - estimate.twist.linear_mps;
        rows.push(StepRow {
            time_secs: log.samples[k].time_secs,
            inputs: step_features(log, k, wheel_radius_m),
            residual,
        });
    }
    Ok(rows)
}

/// Averages consecutive rows over windows of `window_secs`, dropping a
/// trailing window shorter than half its length.
fn windowed(rows: Vec<StepRow>, window_secs: f64) -> Vec<(Vec<f64>, Vector3<f64>)> {
    let Some(t0) = rows.first().map(|r| r.time_secs) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut group: Vec<&StepRow> = Vec::new();
    let flush = |group: &mut Vec<&StepRow>, out: &mut Vec<_>, complete: bool| {
        if group.is_empty() {
            return;
        }
        let span = group[group.len() - 1].time_secs - group[0].time_secs;
        let step = if group.len() > 1 {
            span / (group.len() - 1) as f64
        } else {
            0.0
        };
        if complete || span + step >= 0.5 * window_secs {
            let n = group.len() as f64;
            let d = group[0].inputs.len();
            let mut x = vec![0.0; d];
            let mut y = Vector3::zeros();
            for r in group.iter() {
                for (acc, v) in x.iter_mut().zip(&r.inputs) {
                    *acc += v / n;
                }
                y += r.residual / n;
            }
            out.push((x, y));
        }
        group.clear();
    };
    let mut current = 0u64;
    for row in &rows {
        let w = ((row.time_secs - t0) / window_secs).floor() as u64;
        if w != current {
            flush(&mut group, &mut out, true);
            current = w;
        }
        group.push(row);
    }
    flush(&mut group, &mut out, false);
    out
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
    let Some(first) = logs.first() else {
        return Err(DatasetError::InvalidConfig {
            field: "runs".into(),
            expected: "at least one run".into(),
        });
    };
    let names = feature_names(first);
    let mut inputs = Vec::new();
    let mut targets = Vec::new();
    for log in logs {
        if feature_names(log) != names {
            return Err(DatasetError::InvalidConfig {
                field: format!("runs ({})", log.name),
                expected: format!("the same joints as run {}", first.name),
            });
        }
        let rows = step_rows(log, model, wheel_radius_m)?;
        let rows: Vec<(Vec<f64>, Vector3<f64>)> = match config.window_secs {
            Some(w) => windowed(rows, w),
            None => rows.into_iter().map(|r| (r.inputs, r.residual)).collect(),
        };
        for (x, y) in rows {
            inputs.extend(x);
            let y = if config.absolute_targets { y.abs() } else { y };
            targets.extend(y.iter());
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

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(times: &[f64]) -> Vec<StepRow> {
        times
            .iter()
            .map(|&t| StepRow {
                time_secs: t,
                inputs: vec![t],
                residual: Vector3::new(t, 2.0 * t, 0.0),
            })
            .collect()
    }

    #[test]
    fn windows_average_consecutive_steps_and_drop_a_short_tail() {
        let times: Vec<f64> = (0..11).map(|k| 0.25 * k as f64).collect(); // 0 … 2.5 s
        let out = windowed(rows(&times), 1.0);
        // Windows [0,1), [1,2) are complete; [2,3) holds 2.0, 2.25, 2.5: span
        // 0.75 s ≥ half a window, kept.
        assert_eq!(out.len(), 3);
        assert!((out[0].0[0] - 0.375).abs() < 1e-15);
        assert!((out[1].1.y - 2.0 * 1.375).abs() < 1e-15);
        let out = windowed(rows(&times[..9]), 1.0); // tail 2.0 only
        assert_eq!(out.len(), 2);
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
