//! The measures a rover team reads beside Table II's RMSE: how far the
//! estimate has moved off since the rover last looked, how fast it drifts
//! over a metre and over ten seconds (relative pose error), what a metre
//! costs in compute, and where the RMSE comes from (keyframes, other
//! processed frames, the odometry between them).
//!
//! All are computed from the final trajectory against ground truth at
//! every sensor sample, as [`crate::metrics`] does, and are deterministic.
//!
//! * **Drift since the last look** at sample `k`: `‖e_k − e_j‖`, where
//!   `e = p̂ − p` is the position error and `j` the sample of the last
//!   tracked frame at or before `k` (the start pose, known, before the
//!   first). Its maximum, 95th percentile and root mean square over the
//!   samples.
//! * **Relative pose error** (Sturm et al., IROS 2012, the TUM benchmark's
//!   RPE): for every sample `i` and the first sample `j` at least 1 m of
//!   travel (or 10 s) after it, the translation of
//!   `(T_i⁻¹ T_j)⁻¹ (T̂_i⁻¹ T̂_j)`; the root mean square over `i`.
//! * **CPU per metre**: the compute model's cost (a cost per processed
//!   frame and per keyframe, [`crate::params::ComputeCost`]) over the
//!   ground-truth distance.
//! * **RMSE decomposition**: the RMSE over the samples of keyframes, of
//!   the other processed frames, and of every other sample.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

/// A rover team's measures of one run (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RoverMeasures {
    /// Largest drift since the last tracked frame (m).
    pub drift_since_look_max_m: f64,
    /// 95th percentile of the drift since the last tracked frame (m).
    pub drift_since_look_p95_m: f64,
    /// Root mean square of the drift since the last tracked frame (m): what
    /// the surrogate planner ([`crate::oracle`]) minimises, were every look
    /// exact.
    #[serde(default)]
    pub drift_since_look_rms_m: f64,
    /// RMS translational relative pose error over 1 m of travel (m).
    pub rpe_1m_m: f64,
    /// RMS translational relative pose error over 10 s (m).
    pub rpe_10s_m: f64,
    /// The compute model's cost per metre travelled (ms/m).
    pub cpu_ms_per_m: f64,
    /// Position RMSE at the keyframes' samples (m; 0 without keyframes).
    pub rmse_keyframes_m: f64,
    /// Position RMSE at the other processed frames' samples (m).
    pub rmse_processed_m: f64,
    /// Position RMSE at every sample without a processed frame (m).
    pub rmse_between_m: f64,
}

/// A processed frame, as the measures read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Look {
    /// Time (s).
    pub time_secs: f64,
    /// Whether it became a keyframe.
    pub keyframe: bool,
    /// Whether it was tracked (or relocalised) rather than lost.
    pub tracked: bool,
}

/// The sample, distance and time of a trajectory, as the measures read
/// them.
#[derive(Debug, Clone, Copy)]
pub struct SampledTruth<'a> {
    /// Sample times (s), increasing.
    pub times_secs: &'a [f64],
    /// Ground-truth `world_from_body` at each sample.
    pub ground_truth: &'a [Isometry3<f64>],
    /// Ground-truth distance travelled by each sample (m), non-decreasing.
    pub distance_m: &'a [f64],
}

impl SampledTruth<'_> {
    fn sample_at_or_before(&self, t: f64) -> usize {
        self.times_secs
            .partition_point(|&s| s <= t)
            .saturating_sub(1)
    }
}

/// The measures of `estimate` (one pose per sample of `truth`), with the
/// frames processed in order and the run's compute cost (ms).
pub fn rover_measures(
    estimate: &[Isometry3<f64>],
    truth: &SampledTruth<'_>,
    processed: impl IntoIterator<Item = Look>,
    compute_ms: f64,
) -> RoverMeasures {
    let n = estimate
        .len()
        .min(truth.ground_truth.len())
        .min(truth.times_secs.len())
        .min(truth.distance_m.len());
    if n == 0 {
        return RoverMeasures::default();
    }
    let errors: Vec<_> = (0..n)
        .map(|k| estimate[k].translation.vector - truth.ground_truth[k].translation.vector)
        .collect();

    // Which processed frame, if any, each sample holds (a keyframe wins
    // over a plain frame on the same sample), and the last tracked one.
    #[derive(Clone, Copy, PartialEq)]
    enum At {
        Between,
        Processed,
        Keyframe,
    }
    let mut at = vec![At::Between; n];
    let mut tracked_at = vec![false; n];
    for frame in processed {
        let k = truth.sample_at_or_before(frame.time_secs).min(n - 1);
        if frame.keyframe {
            at[k] = At::Keyframe;
        } else if at[k] == At::Between {
            at[k] = At::Processed;
        }
        tracked_at[k] |= frame.tracked;
    }

    let mut drift = Vec::with_capacity(n);
    let mut last_look = 0;
    for k in 0..n {
        if tracked_at[k] {
            last_look = k;
        }
        drift.push((errors[k] - errors[last_look]).norm());
    }
    let drift_since_look_max_m = drift.iter().copied().fold(0.0, f64::max);
    let drift_since_look_rms_m = (drift.iter().map(|d| d * d).sum::<f64>() / n as f64).sqrt();
    drift.sort_by(f64::total_cmp);
    let drift_since_look_p95_m = percentile_sorted(&drift, 0.95);

    let rmse_over = |class: At| {
        let (sum, count) = (0..n)
            .filter(|&k| at[k] == class)
            .fold((0.0, 0usize), |(s, c), k| {
                (s + errors[k].norm_squared(), c + 1)
            });
        if count == 0 {
            0.0
        } else {
            (sum / count as f64).sqrt()
        }
    };
    let distance = truth.distance_m[n - 1];
    RoverMeasures {
        drift_since_look_max_m,
        drift_since_look_p95_m,
        drift_since_look_rms_m,
        rpe_1m_m: relative_pose_error(estimate, truth, n, |k| truth.distance_m[k], 1.0),
        rpe_10s_m: relative_pose_error(estimate, truth, n, |k| truth.times_secs[k], 10.0),
        cpu_ms_per_m: if distance > 0.0 {
            compute_ms / distance
        } else {
            0.0
        },
        rmse_keyframes_m: rmse_over(At::Keyframe),
        rmse_processed_m: rmse_over(At::Processed),
        rmse_between_m: rmse_over(At::Between),
    }
}

/// RMS translational RPE over every segment from sample `i` to the first
/// sample `j` with `along(j) ≥ along(i) + delta` (`along` non-decreasing);
/// 0 when no segment is that long.
fn relative_pose_error(
    estimate: &[Isometry3<f64>],
    truth: &SampledTruth<'_>,
    n: usize,
    along: impl Fn(usize) -> f64,
    delta: f64,
) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    let mut j = 0;
    for i in 0..n {
        j = j.max(i);
        while j < n && along(j) < along(i) + delta {
            j += 1;
        }
        if j == n {
            break;
        }
        let true_motion = truth.ground_truth[i].inverse() * truth.ground_truth[j];
        let estimated_motion = estimate[i].inverse() * estimate[j];
        let error = true_motion.inverse() * estimated_motion;
        sum += error.translation.vector.norm_squared();
        count += 1;
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt()
    }
}

/// The `q`-quantile of sorted values, linearly interpolated (NumPy's
/// default); 0 when empty.
fn percentile_sorted(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => 0.0,
        len => {
            let position = q * (len - 1) as f64;
            let (lo, hi) = (position.floor() as usize, position.ceil() as usize);
            sorted[lo] + (sorted[hi] - sorted[lo]) * (position - lo as f64)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    fn frame(time_secs: f64, keyframe: bool, tracked: bool) -> Look {
        Look {
            time_secs,
            keyframe,
            tracked,
        }
    }

    /// Times, truth, distances and an estimate.
    type Route = (Vec<f64>, Vec<Isometry3<f64>>, Vec<f64>, Vec<Isometry3<f64>>);

    /// Truth: 0.5 m/s along x, sampled at 1 s, for 5 s. The estimate is
    /// off by 0, 0.1 (x), 0.1, 0.3 (x), 0.3, 0.2 (y) m.
    fn line() -> Route {
        let times: Vec<f64> = (0..6).map(f64::from).collect();
        let truth: Vec<_> = times
            .iter()
            .map(|t| Isometry3::translation(0.5 * t, 0.0, 0.0))
            .collect();
        let distance: Vec<f64> = times.iter().map(|t| 0.5 * t).collect();
        let offsets = [
            Vector3::zeros(),
            Vector3::new(0.1, 0.0, 0.0),
            Vector3::new(0.1, 0.0, 0.0),
            Vector3::new(0.3, 0.0, 0.0),
            Vector3::new(0.3, 0.0, 0.0),
            Vector3::new(0.0, 0.2, 0.0),
        ];
        let estimate = truth
            .iter()
            .zip(offsets)
            .map(|(t, o)| Isometry3::from_parts((t.translation.vector + o).into(), t.rotation))
            .collect();
        (times, truth, distance, estimate)
    }

    #[test]
    fn measures_match_a_hand_computation() {
        let (times, truth, distance, estimate) = line();
        let sampled = SampledTruth {
            times_secs: &times,
            ground_truth: &truth,
            distance_m: &distance,
        };
        // A keyframe tracked at 2 s, a plain frame tracked at 3.5 s (sample
        // 3), a lost frame at 4 s.
        let processed = [
            frame(2.0, true, true),
            frame(3.5, false, true),
            frame(4.0, false, false),
        ];
        let m = rover_measures(&estimate, &sampled, processed, 500.0);
        // Drift since the last look: samples 0–1 from the start (0, 0.1),
        // sample 2 looks (0), sample 3 looks (0), 4 from 3 (0), 5 from 3:
        // ‖(0, 0.2) − (0.3, 0)‖ = √0.13.
        let drift = [0.0, 0.1, 0.0, 0.0, 0.0, 0.13f64.sqrt()];
        assert!((m.drift_since_look_max_m - 0.13f64.sqrt()).abs() < 1e-12);
        let mut sorted = drift.to_vec();
        sorted.sort_by(f64::total_cmp);
        // q = 0.95 over 6 values: position 4.75 between 0.1 and √0.13.
        let p95 = 0.1 + (0.13f64.sqrt() - 0.1) * 0.75;
        assert!((m.drift_since_look_p95_m - p95).abs() < 1e-12);
        let rms = ((0.01 + 0.13) / 6.0f64).sqrt();
        assert!((m.drift_since_look_rms_m - rms).abs() < 1e-12);
        // RPE over 1 m: pairs (0,2), (1,3), (2,4), (3,5); no rotation, so
        // the error is the difference of the offsets' differences.
        let d = |a: Vector3<f64>, b: Vector3<f64>| (b - a).norm_squared();
        let o = |x: f64, y: f64| Vector3::new(x, y, 0.0);
        let rpe1 = ((d(o(0.0, 0.0), o(0.1, 0.0))
            + d(o(0.1, 0.0), o(0.3, 0.0))
            + d(o(0.1, 0.0), o(0.3, 0.0))
            + d(o(0.3, 0.0), o(0.0, 0.2)))
            / 4.0)
            .sqrt();
        assert!((m.rpe_1m_m - rpe1).abs() < 1e-12);
        // 10 s is longer than the run.
        assert_eq!(m.rpe_10s_m, 0.0);
        assert!((m.cpu_ms_per_m - 500.0 / 2.5).abs() < 1e-12);
        // Keyframe at sample 2 (0.1), plain frames at 3 (0.3) and 4 (0.3),
        // the rest between: 0, 0.1, 0.2.
        assert!((m.rmse_keyframes_m - 0.1).abs() < 1e-12);
        assert!((m.rmse_processed_m - 0.3).abs() < 1e-12);
        let between = ((0.0 + 0.01 + 0.04) / 3.0f64).sqrt();
        assert!((m.rmse_between_m - between).abs() < 1e-12);
    }

    #[test]
    fn relative_pose_error_is_expressed_in_the_first_pose_frame() {
        // The rover faces +y; the estimate overshoots each metre by 1 cm
        // along its heading. The RPE over 1 m is 1 cm whatever the frame.
        let yaw = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let times: Vec<f64> = (0..4).map(f64::from).collect();
        let truth: Vec<_> = times
            .iter()
            .map(|t| Isometry3::from_parts(Vector3::new(0.0, *t, 0.0).into(), yaw))
            .collect();
        let estimate: Vec<_> = times
            .iter()
            .map(|t| Isometry3::from_parts(Vector3::new(0.0, 1.01 * t, 0.0).into(), yaw))
            .collect();
        let sampled = SampledTruth {
            times_secs: &times,
            ground_truth: &truth,
            distance_m: &times,
        };
        let m = rover_measures(&estimate, &sampled, [], 0.0);
        assert!((m.rpe_1m_m - 0.01).abs() < 1e-12);
        // Nothing processed: every sample is between frames, and the drift
        // since the last look is the error itself.
        assert!((m.drift_since_look_max_m - 0.03).abs() < 1e-12);
        assert_eq!(m.rmse_keyframes_m, 0.0);
    }
}
