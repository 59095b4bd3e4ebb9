//! Dead reckoning with a motion model: integrate its body twists from the
//! first ground-truth pose and compare the end point with ground truth, the
//! "travel distance error %" of the paper's Table II for odometry alone.

use gpodo_datasets::log::RoverLog;
use gpodo_traits::MotionModel;
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

/// How far pure odometry drifts over a run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DeadReckoning {
    /// Ground-truth path length (m).
    pub distance_m: f64,
    /// Distance between the odometry's and the ground truth's final
    /// positions (m).
    pub final_error_m: f64,
    /// `final_error_m / distance_m` in percent.
    pub final_error_percent: f64,
    /// Largest position error along the run (m).
    pub max_error_m: f64,
}

/// Integrates `model` over `log`, starting from the first ground-truth pose.
///
/// # Errors
/// Whatever the model returns for a sample it cannot handle.
pub fn dead_reckoning(
    log: &RoverLog,
    model: &dyn MotionModel,
) -> Result<DeadReckoning, gpodo_traits::Error> {
    log.validate()
        .map_err(|e| gpodo_traits::Error::InvalidInput(e.to_string()))?;
    let Some(first) = log.ground_truth.first() else {
        return Err(gpodo_traits::Error::InvalidInput(format!(
            "run {} is empty",
            log.name
        )));
    };
    let mut pose: Isometry3<f64> = *first;
    let mut max_error: f64 = 0.0;
    for k in 0..log.samples.len().saturating_sub(1) {
        let dt = log.samples[k + 1].time_secs - log.samples[k].time_secs;
        let twist = model.estimate(&log.samples[k], dt)?.twist;
        pose *= twist.pose_delta(dt);
        let error = (pose.translation.vector - log.ground_truth[k + 1].translation.vector).norm();
        max_error = max_error.max(error);
    }
    let last = log.ground_truth.last().unwrap_or(first);
    let final_error_m = (pose.translation.vector - last.translation.vector).norm();
    let distance_m = log.path_length_m();
    Ok(DeadReckoning {
        distance_m,
        final_error_m,
        final_error_percent: 100.0 * final_error_m / distance_m.max(f64::MIN_POSITIVE),
        max_error_m: max_error,
    })
}
