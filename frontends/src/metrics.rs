//! Trajectory error metrics of Table II: RMSE, maximum and final position
//! error against ground truth, and the final error as a percentage of the
//! distance travelled. Errors are compared at every sensor sample, without
//! alignment: the run starts from the known first pose.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

/// Position errors of an estimated trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TrajectoryMetrics {
    /// Root-mean-square position error over the samples (m).
    pub rmse_m: f64,
    /// Largest position error (m).
    pub max_error_m: f64,
    /// Position error at the last sample (m).
    pub final_error_m: f64,
    /// Ground-truth distance travelled (m).
    pub distance_m: f64,
    /// `100 · final_error_m / distance_m`: the paper's travel-distance
    /// error.
    pub travel_distance_error_percent: f64,
}

/// Compares `estimate` with `truth`, sample by sample (same length);
/// `distance_m` is the distance travelled (the traverse's path length).
pub fn trajectory_metrics(
    estimate: &[Isometry3<f64>],
    truth: &[Isometry3<f64>],
    distance_m: f64,
) -> TrajectoryMetrics {
    let n = estimate.len().min(truth.len());
    if n == 0 {
        return TrajectoryMetrics::default();
    }
    let errors: Vec<f64> = estimate
        .iter()
        .zip(truth)
        .map(|(e, t)| (e.translation.vector - t.translation.vector).norm())
        .collect();
    let final_error_m = errors[n - 1];
    TrajectoryMetrics {
        rmse_m: (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt(),
        max_error_m: errors.iter().copied().fold(0.0, f64::max),
        final_error_m,
        distance_m,
        travel_distance_error_percent: if distance_m > 0.0 {
            100.0 * final_error_m / distance_m
        } else {
            0.0
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_match_a_hand_computation() {
        // Truth: 0, 1, 2, 3 m along x. Estimate off by 0, 0.3 (y), 0.4 (z),
        // 0.5 (x) m.
        let truth: Vec<Isometry3<f64>> = (0..4)
            .map(|k| Isometry3::translation(k as f64, 0.0, 0.0))
            .collect();
        let estimate = vec![
            Isometry3::translation(0.0, 0.0, 0.0),
            Isometry3::translation(1.0, 0.3, 0.0),
            Isometry3::translation(2.0, 0.0, 0.4),
            Isometry3::translation(3.5, 0.0, 0.0),
        ];
        let m = trajectory_metrics(&estimate, &truth, 3.0);
        let rmse = ((0.09 + 0.16 + 0.25) / 4.0f64).sqrt();
        assert!((m.rmse_m - rmse).abs() < 1e-15);
        assert_eq!(m.max_error_m, 0.5);
        assert_eq!(m.final_error_m, 0.5);
        assert_eq!(m.distance_m, 3.0);
        assert!((m.travel_distance_error_percent - 100.0 * 0.5 / 3.0).abs() < 1e-12);
    }
}
