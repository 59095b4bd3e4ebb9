//! A guard around any policy: process a frame whenever too much time (or
//! odometry distance, or rotation) has passed since the last processed one,
//! whatever the inner policy says — so a confident but wrong model cannot
//! leave the tracker blind for long.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use serde::{Deserialize, Serialize};

use super::{TIME_TOLERANCE_SECS, process_if_due, since_processed};
use crate::FrontendError;

/// Limits of [`MaxGap`]; each is off when `null`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MaxGapParams {
    /// Longest time between processed frames (s; default 4).
    pub max_gap_secs: Option<f64>,
    /// Longest odometry distance between processed frames (m; default off).
    pub max_distance_m: Option<f64>,
    /// Largest odometry rotation between processed frames (rad; default off).
    pub max_rotation_rad: Option<f64>,
}

impl Default for MaxGapParams {
    fn default() -> Self {
        Self {
            max_gap_secs: Some(4.0),
            max_distance_m: None,
            max_rotation_rad: None,
        }
    }
}

impl MaxGapParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        for (field, v) in [
            ("max_gap_secs", self.max_gap_secs),
            ("max_distance_m", self.max_distance_m),
            ("max_rotation_rad", self.max_rotation_rad),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(FrontendError::InvalidSpec {
                    selector: "max_gap".into(),
                    field: field.into(),
                    expected: "a positive limit, or null".into(),
                });
            }
        }
        if self.max_gap_secs.is_none()
            && self.max_distance_m.is_none()
            && self.max_rotation_rad.is_none()
        {
            return Err(FrontendError::InvalidSpec {
                selector: "max_gap".into(),
                field: "max_gap_secs".into(),
                expected: "at least one limit (max_gap_secs, max_distance_m or max_rotation_rad)"
                    .into(),
            });
        }
        Ok(())
    }
}

/// The guard.
pub struct MaxGap {
    inner: Box<dyn FrameSelector>,
    params: MaxGapParams,
    name: String,
}

impl MaxGap {
    /// Guards `inner`.
    ///
    /// # Errors
    /// As [`MaxGapParams::validate`].
    pub fn new(inner: Box<dyn FrameSelector>, params: MaxGapParams) -> Result<Self, FrontendError> {
        params.validate()?;
        let name = format!("max_gap[{}]", inner.name());
        Ok(Self {
            inner,
            params,
            name,
        })
    }

    fn exceeded(&self, ctx: &FrameContext) -> bool {
        let p = &self.params;
        p.max_gap_secs
            .is_some_and(|g| since_processed(ctx) + TIME_TOLERANCE_SECS >= g)
            || p.max_distance_m
                .is_some_and(|d| ctx.distance_since_processed_m >= d)
            || p.max_rotation_rad
                .is_some_and(|r| ctx.rotation_since_processed_rad >= r)
    }
}

impl FrameSelector for MaxGap {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let inner = self.inner.decide(ctx);
        process_if_due(inner, self.exceeded(ctx))
    }

    fn reset(&mut self) {
        self.inner.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::run;
    use super::super::{UncertaintyBudget, UncertaintyBudgetParams};
    use super::*;

    fn never_after_first() -> Box<dyn FrameSelector> {
        Box::new(UncertaintyBudget::new(UncertaintyBudgetParams::default()).unwrap())
    }

    #[test]
    fn the_guard_fills_gaps_the_inner_policy_leaves() {
        let mut s = MaxGap::new(never_after_first(), MaxGapParams::default()).unwrap();
        assert_eq!(s.name(), "max_gap[uncertainty_budget]");
        let times = run(&mut s, 20.0, |_| 0.0);
        assert_eq!(times.len(), 5, "{times:?}");
        for w in times.windows(2) {
            assert!((w[1] - w[0] - 4.0).abs() < 1e-9, "{times:?}");
        }
    }

    #[test]
    fn distance_limit_works_alone() {
        // test_support drives at 4 cm/s: 0.1 m every 2.5 s.
        let params = MaxGapParams {
            max_gap_secs: None,
            max_distance_m: Some(0.1),
            max_rotation_rad: None,
        };
        let mut s = MaxGap::new(never_after_first(), params).unwrap();
        let times = run(&mut s, 10.0, |_| 0.0);
        assert_eq!(times.len(), 4, "{times:?}");
    }

    #[test]
    fn at_least_one_limit_is_required() {
        let params = MaxGapParams {
            max_gap_secs: None,
            ..Default::default()
        };
        assert!(MaxGap::new(never_after_first(), params).is_err());
    }
}
