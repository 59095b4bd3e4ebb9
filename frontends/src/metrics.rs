//! Trajectory error metrics of Table II: RMSE, maximum and final position
//! error against ground truth, and the final error as a percentage of the
//! distance travelled. Errors are compared at every sensor sample, without
//! alignment: the run starts from the known first pose. Also how alike two
//! estimates of one route err ([`error_agreement`]), which the A/A control
//! reads.

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

/// How much two estimates of one route err alike: the errors of two
/// schedules that look at the same ground through different frames.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ErrorAgreement {
    /// Pearson correlation of the two position errors, over every sample
    /// and axis (each axis's errors centred on their mean).
    pub correlation: f64,
    /// The share of the error's second moment the two have in common:
    /// `2 Σ e_a·e_b / Σ (|e_a|² + |e_b|²)` over the samples (uncentred, as
    /// the RMSE is). 1 when the errors are the same, 0 when orthogonal,
    /// and the variance of `RMSE_a − RMSE_b` shrinks as it grows.
    pub shared_share: f64,
}

/// The agreement of the position errors of `a` and `b` against `truth`,
/// sample by sample (the shortest length).
pub fn error_agreement(
    a: &[Isometry3<f64>],
    b: &[Isometry3<f64>],
    truth: &[Isometry3<f64>],
) -> ErrorAgreement {
    let n = a.len().min(b.len()).min(truth.len());
    if n < 2 {
        return ErrorAgreement::default();
    }
    let error =
        |e: &Isometry3<f64>, t: &Isometry3<f64>| e.translation.vector - t.translation.vector;
    let ea: Vec<_> = a[..n].iter().zip(truth).map(|(e, t)| error(e, t)).collect();
    let eb: Vec<_> = b[..n].iter().zip(truth).map(|(e, t)| error(e, t)).collect();
    let mean = |v: &[nalgebra::Vector3<f64>]| v.iter().sum::<nalgebra::Vector3<f64>>() / n as f64;
    let (ma, mb) = (mean(&ea), mean(&eb));
    let (mut cross, mut va, mut vb, mut raw_cross, mut raw_sq) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (x, y) in ea.iter().zip(&eb) {
        let (dx, dy) = (x - ma, y - mb);
        cross += dx.dot(&dy);
        va += dx.norm_squared();
        vb += dy.norm_squared();
        raw_cross += x.dot(y);
        raw_sq += x.norm_squared() + y.norm_squared();
    }
    ErrorAgreement {
        correlation: if va > 0.0 && vb > 0.0 {
            cross / (va * vb).sqrt()
        } else {
            0.0
        },
        shared_share: if raw_sq > 0.0 {
            2.0 * raw_cross / raw_sq
        } else {
            0.0
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agreement_of_the_same_opposite_and_orthogonal_errors() {
        let truth: Vec<Isometry3<f64>> = (0..4)
            .map(|k| Isometry3::translation(k as f64, 0.0, 0.0))
            .collect();
        let off = |d: &[(f64, f64)]| -> Vec<Isometry3<f64>> {
            truth
                .iter()
                .zip(d)
                .map(|(t, (x, y))| Isometry3::translation(t.translation.x + x, *y, 0.0))
                .collect()
        };
        let a = off(&[(0.0, 0.0), (0.1, 0.0), (0.3, 0.0), (0.2, 0.0)]);
        let same = error_agreement(&a, &a, &truth);
        assert!((same.correlation - 1.0).abs() < 1e-12);
        assert!((same.shared_share - 1.0).abs() < 1e-12);
        let opposite = off(&[(0.0, 0.0), (-0.1, 0.0), (-0.3, 0.0), (-0.2, 0.0)]);
        let o = error_agreement(&a, &opposite, &truth);
        assert!((o.correlation + 1.0).abs() < 1e-12);
        assert!((o.shared_share + 1.0).abs() < 1e-12);
        // Along y instead of x: no shared moment; the centred correlation
        // over the six axis series is also 0 (x and y are centred apart).
        let across = off(&[(0.0, 0.0), (0.0, 0.1), (0.0, 0.3), (0.0, 0.2)]);
        let c = error_agreement(&a, &across, &truth);
        assert!(c.shared_share.abs() < 1e-12);
        assert!(c.correlation.abs() < 1e-12);
        // Half the size, same direction: correlation 1, shared moment
        // 2·0.5/(1 + 0.25) = 0.8.
        let half = off(&[(0.0, 0.0), (0.05, 0.0), (0.15, 0.0), (0.1, 0.0)]);
        let h = error_agreement(&a, &half, &truth);
        assert!((h.correlation - 1.0).abs() < 1e-12);
        assert!((h.shared_share - 0.8).abs() < 1e-12);
    }

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
