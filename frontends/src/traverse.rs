//! What the front end runs on: one traverse of the rover with its
//! ground truth (for the simulated visual odometry and the metrics), the
//! motion model's body twist for every sensor step (the wheel odometry
//! `g` of eq. 11), the residual-regressor inputs averaged over windows
//! (§IV-C) and the camera frame times (§V-B).

use std::ops::Range;

use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};

use crate::FrontendError;

/// One window of sensor steps, as the regressors see it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraverseWindow {
    /// Start (s).
    pub start_secs: f64,
    /// End (s); a prediction from this window's inputs is available from
    /// here on.
    pub end_secs: f64,
    /// The steps it averages.
    pub steps: Range<usize>,
    /// The regressor inputs (standardised as the regressors were trained).
    pub inputs: Vec<f64>,
    /// The true residual over the window (m/s, body frame), for plots and
    /// the oracle; never read by a causal policy.
    pub true_residual: Vector3<f64>,
}

/// A traverse, checked for consistency by [`Traverse::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Traverse {
    name: String,
    times_secs: Vec<f64>,
    ground_truth: Vec<Isometry3<f64>>,
    twists: Vec<BodyTwist>,
    windows: Vec<TraverseWindow>,
    camera_times_secs: Vec<f64>,
    /// Cumulative ground-truth path length at each sample (m).
    cumulative_m: Vec<f64>,
    /// Whether the windows' inputs are z-scored (see
    /// [`Traverse::with_standardized_inputs`]).
    inputs_standardized: bool,
    /// Feature supply at each camera frame (see
    /// [`Traverse::with_feature_supply`]); `None` is neutral.
    #[serde(default)]
    feature_supply: Option<Vec<f64>>,
}

/// Stride over which the path length is measured (s): summing sample-to-
/// sample steps would add up the ground truth's jitter.
pub const PATH_STRIDE_SECS: f64 = 1.0;

/// Path length up to each sample: straight segments between anchors at
/// least [`PATH_STRIDE_SECS`] apart, interpolated in time between them.
fn cumulative_distance(times: &[f64], truth: &[Isometry3<f64>]) -> Vec<f64> {
    let n = times.len();
    let mut anchors = vec![0];
    for k in 1..n {
        if times[k] - times[anchors[anchors.len() - 1]] >= PATH_STRIDE_SECS || k == n - 1 {
            anchors.push(k);
        }
    }
    let mut out = vec![0.0; n];
    let mut acc = 0.0;
    for w in anchors.windows(2) {
        let (a, b) = (w[0], w[1]);
        let segment = (truth[b].translation.vector - truth[a].translation.vector).norm();
        for k in a..=b {
            out[k] = acc + segment * (times[k] - times[a]) / (times[b] - times[a]);
        }
        acc += segment;
    }
    out
}

impl Traverse {
    /// Checks and builds a traverse: `times_secs` strictly increasing,
    /// one ground-truth pose per sample, one twist per step (`n − 1`),
    /// windows in time order over valid step ranges, camera frames strictly
    /// increasing inside the sampled time span.
    ///
    /// # Errors
    /// [`FrontendError::InvalidTraverse`] naming what is inconsistent.
    pub fn new(
        name: impl Into<String>,
        times_secs: Vec<f64>,
        ground_truth: Vec<Isometry3<f64>>,
        twists: Vec<BodyTwist>,
        windows: Vec<TraverseWindow>,
        camera_times_secs: Vec<f64>,
    ) -> Result<Self, FrontendError> {
        let name = name.into();
        let bad = |detail: String| FrontendError::InvalidTraverse {
            traverse: name.clone(),
            detail,
        };
        let n = times_secs.len();
        if n < 2 {
            return Err(bad(format!("needs at least 2 samples, has {n}")));
        }
        if let Some(k) = times_secs
            .windows(2)
            .position(|w| !(w[1] > w[0] && w[1].is_finite() && w[0].is_finite()))
        {
            return Err(bad(format!(
                "sample times not strictly increasing at sample {}",
                k + 1
            )));
        }
        if ground_truth.len() != n {
            return Err(bad(format!(
                "{} ground-truth poses for {n} samples",
                ground_truth.len()
            )));
        }
        if twists.len() != n - 1 {
            return Err(bad(format!(
                "{} odometry twists for {} steps",
                twists.len(),
                n - 1
            )));
        }
        let mut previous_end = 0;
        for (i, w) in windows.iter().enumerate() {
            if w.steps.start < previous_end || w.steps.end > n - 1 || w.steps.is_empty() {
                return Err(bad(format!(
                    "window {i} covers steps {:?} out of order or range",
                    w.steps
                )));
            }
            if w.end_secs.partial_cmp(&w.start_secs) != Some(std::cmp::Ordering::Greater) {
                return Err(bad(format!("window {i} ends before it starts")));
            }
            previous_end = w.steps.end;
        }
        if let Some(k) = camera_times_secs.windows(2).position(|w| w[1] <= w[0]) {
            return Err(bad(format!(
                "camera times not strictly increasing at frame {}",
                k + 1
            )));
        }
        let (t0, t1) = (times_secs[0], times_secs[n - 1]);
        if camera_times_secs.iter().any(|t| !(*t >= t0 && *t <= t1)) {
            return Err(bad(format!(
                "camera frames outside the sampled span [{t0}, {t1}] s"
            )));
        }
        let cumulative_m = cumulative_distance(&times_secs, &ground_truth);
        Ok(Self {
            name,
            times_secs,
            ground_truth,
            twists,
            windows,
            camera_times_secs,
            cumulative_m,
            inputs_standardized: false,
            feature_supply: None,
        })
    }

    /// The same traverse, its window inputs marked as z-scored with the
    /// training rows' statistics: an online learner then hands its
    /// regressor rows whose inputs are not z-scored again.
    #[must_use]
    pub fn with_standardized_inputs(mut self, standardized: bool) -> Self {
        self.inputs_standardized = standardized;
        self
    }

    /// The same traverse with a feature supply per camera frame: the
    /// matchable features the terrain and the motion leave, relative to
    /// the reference texture (1; see `frontends/README.md`). A traverse
    /// without one (a replayed or recorded run) is neutral.
    ///
    /// # Errors
    /// [`FrontendError::InvalidTraverse`] when the length differs from the
    /// camera frames' or a value is not positive and finite.
    pub fn with_feature_supply(mut self, supply: Vec<f64>) -> Result<Self, FrontendError> {
        let bad = |detail: String| FrontendError::InvalidTraverse {
            traverse: self.name.clone(),
            detail,
        };
        if supply.len() != self.camera_times_secs.len() {
            return Err(bad(format!(
                "{} feature-supply values for {} camera frames",
                supply.len(),
                self.camera_times_secs.len()
            )));
        }
        if let Some(i) = supply.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(bad(format!(
                "feature supply {} at camera frame {i}, expected a positive number",
                supply[i]
            )));
        }
        self.feature_supply = Some(supply);
        Ok(self)
    }

    /// The feature supply of camera frame `index` (1 without one, or
    /// outside the camera stream).
    pub fn feature_supply_at(&self, index: usize) -> f64 {
        self.feature_supply
            .as_ref()
            .and_then(|s| s.get(index).copied())
            .unwrap_or(1.0)
    }

    /// Whether the window inputs are z-scored.
    pub fn inputs_standardized(&self) -> bool {
        self.inputs_standardized
    }

    /// The traverse's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Sample times (s).
    pub fn times_secs(&self) -> &[f64] {
        &self.times_secs
    }

    /// Ground-truth `world_from_body` at each sample.
    pub fn ground_truth(&self) -> &[Isometry3<f64>] {
        &self.ground_truth
    }

    /// The motion model's twist over each step (`n − 1`).
    pub fn twists(&self) -> &[BodyTwist] {
        &self.twists
    }

    /// The regressor windows, in time order.
    pub fn windows(&self) -> &[TraverseWindow] {
        &self.windows
    }

    /// Camera frame times (s).
    pub fn camera_times_secs(&self) -> &[f64] {
        &self.camera_times_secs
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times_secs.len()
    }

    /// Always false: a traverse has at least two samples.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Ground-truth path length up to sample `k` (m).
    pub fn distance_at(&self, k: usize) -> f64 {
        self.cumulative_m[k]
    }

    /// Ground-truth path length up to each sample (m).
    pub fn distances_m(&self) -> &[f64] {
        &self.cumulative_m
    }

    /// Ground-truth path length of the whole traverse (m), over 1-s
    /// strides.
    pub fn path_length_m(&self) -> f64 {
        self.cumulative_m[self.cumulative_m.len() - 1]
    }

    /// The sample at or before `t` (clamped to the first sample).
    pub fn sample_at_or_before(&self, t: f64) -> usize {
        self.times_secs
            .partition_point(|&s| s <= t)
            .saturating_sub(1)
    }

    /// Ground truth at time `t`, interpolated between samples (linear in
    /// position, spherical in rotation), clamped to the sampled span.
    pub fn ground_truth_at(&self, t: f64) -> Isometry3<f64> {
        let k = self.sample_at_or_before(t);
        if k + 1 >= self.len() {
            return self.ground_truth[self.len() - 1];
        }
        let (ta, tb) = (self.times_secs[k], self.times_secs[k + 1]);
        let s = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
        let (a, b) = (&self.ground_truth[k], &self.ground_truth[k + 1]);
        a.lerp_slerp(b, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Traverse {
        let times: Vec<f64> = (0..n).map(|k| 0.1 * k as f64).collect();
        let gt = times
            .iter()
            .map(|t| Isometry3::translation(0.05 * t, 0.0, 0.0))
            .collect();
        Traverse::new(
            "line",
            times,
            gt,
            vec![BodyTwist::default(); n - 1],
            vec![],
            vec![0.0, 0.5],
        )
        .unwrap()
    }

    #[test]
    fn path_length_and_interpolated_ground_truth() {
        let t = line(11);
        assert!((t.path_length_m() - 0.05).abs() < 1e-12);
        let p = t.ground_truth_at(0.25);
        assert!((p.translation.vector.x - 0.0125).abs() < 1e-12);
        assert_eq!(t.sample_at_or_before(0.25), 2);
        assert_eq!(t.sample_at_or_before(-1.0), 0);
        assert_eq!(t.ground_truth_at(5.0), t.ground_truth()[10]);
    }

    #[test]
    fn inconsistent_inputs_are_rejected_with_what_is_wrong() {
        let times = vec![0.0, 0.1, 0.1];
        let gt = vec![Isometry3::identity(); 3];
        let err = Traverse::new(
            "x",
            times,
            gt.clone(),
            vec![BodyTwist::default(); 2],
            vec![],
            vec![],
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("strictly increasing at sample 2"),
            "{err}"
        );
        let err = Traverse::new(
            "x",
            vec![0.0, 0.1, 0.2],
            gt,
            vec![BodyTwist::default(); 2],
            vec![],
            vec![0.5],
        )
        .unwrap_err();
        assert!(err.to_string().contains("camera frames outside"), "{err}");
    }
}
