//! Process a frame when the odometry drift the regressor expects since the
//! last processed frame — the predicted residual's mean² plus variance,
//! integrated along the path as a squared displacement (see
//! [`crate::odometry`]) — exceeds a budget. Where the wheels are trusted
//! the rover looks rarely; where they slip, or where an online model is
//! still uncertain, it looks often.
//!
//! The drift counted is that of the odometry the pose graph uses, so it
//! follows the scheme's odometry mode ([`crate::odometry_mode`]): where the
//! predicted mean corrects the wheels, only the variance left counts (a
//! model that has learned a large but steady residual stops asking for
//! frames, and only what it does not know costs frames); where nothing is
//! corrected (the authors' odometry), the mean² counts too. `count_mean`
//! may state it; a value that contradicts the mode is an error
//! ([`crate::SelectorSpec::for_odometry`]).

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use serde::{Deserialize, Serialize};

use super::{TIME_TOLERANCE_SECS, since_processed};
use crate::FrontendError;

/// Settings of [`UncertaintyBudget`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UncertaintyBudgetParams {
    /// Expected squared displacement error allowed between processed
    /// frames (m²; default 2.5e-5, i.e. 5 mm).
    pub budget_m2: f64,
    /// Shortest period between processed frames (s; default 0.4).
    pub min_period_secs: f64,
    /// Count the predicted mean² in the drift (the uncorrected odometry's
    /// error) or the variance alone (the corrected odometry's). Default
    /// null: as the scheme's odometry mode says (false when the mean
    /// corrects the odometry, true when it does not); a policy built
    /// outside a scheme counts the variance alone.
    pub count_mean: Option<bool>,
}

impl Default for UncertaintyBudgetParams {
    fn default() -> Self {
        Self {
            budget_m2: 2.5e-5,
            min_period_secs: 0.4,
            count_mean: None,
        }
    }
}

impl UncertaintyBudgetParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidSpec {
                selector: "uncertainty_budget".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if !(self.budget_m2.is_finite() && self.budget_m2 > 0.0) {
            return bad("budget_m2", "a positive squared distance in m²");
        }
        if !(self.min_period_secs.is_finite() && self.min_period_secs >= 0.0) {
            return bad("min_period_secs", "a non-negative period in s");
        }
        Ok(())
    }
}

/// The drift-budget policy.
#[derive(Debug, Clone, PartialEq)]
pub struct UncertaintyBudget {
    params: UncertaintyBudgetParams,
}

impl UncertaintyBudget {
    /// A policy with checked settings.
    ///
    /// # Errors
    /// As [`UncertaintyBudgetParams::validate`].
    pub fn new(params: UncertaintyBudgetParams) -> Result<Self, FrontendError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl FrameSelector for UncertaintyBudget {
    fn name(&self) -> &str {
        "uncertainty_budget"
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        if ctx.last_processed_secs.is_none() {
            return FrameDecision::PROCESS;
        }
        if since_processed(ctx) + TIME_TOLERANCE_SECS < self.params.min_period_secs {
            return FrameDecision::Skip;
        }
        let drift = if self.params.count_mean.unwrap_or(false) {
            ctx.drift_since_processed
        } else {
            ctx.drift_variance_since_processed
        };
        if drift >= self.params.budget_m2 {
            FrameDecision::PROCESS
        } else {
            FrameDecision::Skip
        }
    }

    fn reset(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::super::test_support::run;
    use super::*;

    #[test]
    fn frames_follow_the_accumulated_drift() {
        // test_support accumulates r² · 0.1 per frame: with r = 0.01 m/s a
        // budget of 1e-4 is reached after 10 frames (1 s).
        let mut s = UncertaintyBudget::new(UncertaintyBudgetParams {
            budget_m2: 1e-4,
            min_period_secs: 0.0,
            count_mean: Some(true),
        })
        .unwrap();
        let times = run(&mut s, 10.0, |_| 0.01);
        assert_eq!(times.len(), 10, "{times:?}");
        // Twice the residual: four times the drift rate, every 3 frames.
        let times = run(&mut s, 10.0, |_| 0.02);
        assert_eq!(times.len(), 34, "{times:?}");
    }

    #[test]
    fn no_drift_processes_only_the_first_frame_and_the_floor_holds() {
        let mut s = UncertaintyBudget::new(UncertaintyBudgetParams {
            count_mean: Some(true),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(run(&mut s, 30.0, |_| 0.0), vec![0.0]);
        let times = run(&mut s, 10.0, |_| 1.0);
        assert_eq!(times.len(), 25, "min period 0.4 s: {times:?}");
    }

    #[test]
    fn without_the_mean_only_the_variance_drift_counts() {
        let mut s = UncertaintyBudget::new(UncertaintyBudgetParams {
            budget_m2: 1e-4,
            min_period_secs: 0.0,
            count_mean: Some(false),
        })
        .unwrap();
        let ctx = |drift, variance_drift| FrameContext {
            time_secs: 5.0,
            last_processed_secs: Some(0.0),
            drift_since_processed: drift,
            drift_variance_since_processed: variance_drift,
            ..Default::default()
        };
        assert_eq!(s.decide(&ctx(1.0, 5e-5)), FrameDecision::Skip);
        assert!(s.decide(&ctx(1.0, 2e-4)).is_process());
    }

    #[test]
    fn a_non_positive_budget_is_rejected() {
        let err = UncertaintyBudget::new(UncertaintyBudgetParams {
            budget_m2: 0.0,
            ..Default::default()
        })
        .unwrap_err();
        assert!(err.to_string().contains("budget_m2"), "{err}");
    }
}
