//! Looking more often while lost: the authors' adaptive mode processes
//! every frame of its 2.5 fps input stream while tracking is not OK
//! (`slam-orogen-adaptive_slam`, `Task.cpp`, `updateFrameFrequency`). This
//! wrapper gives any gated policy that behaviour: while
//! [`FrameContext::tracking_lost`], a frame is processed whenever
//! `period_secs` have passed since the last processed one, whatever the
//! inner policy says. Fixed-rate baselines are not wrapped: they keep
//! their rate, as the authors' did.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};

use super::{TIME_TOLERANCE_SECS, process_if_due, since_processed};
use crate::FrontendError;

/// The authors' camera period while lost (s): their 2.5 fps input stream.
pub const AUTHORS_LOST_PERIOD_SECS: f64 = 0.4;

/// The wrapper.
pub struct WhileLost {
    inner: Box<dyn FrameSelector>,
    period_secs: f64,
    name: String,
}

impl WhileLost {
    /// Wraps `inner`: while lost, a frame every `period_secs`.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] for a period that is not positive.
    pub fn new(inner: Box<dyn FrameSelector>, period_secs: f64) -> Result<Self, FrontendError> {
        if !(period_secs.is_finite() && period_secs > 0.0) {
            return Err(FrontendError::InvalidConfig {
                field: "lost_frame_period_secs".into(),
                expected: "a positive period in s, or null".into(),
            });
        }
        let name = format!("while_lost[{}]", inner.name());
        Ok(Self {
            inner,
            period_secs,
            name,
        })
    }
}

impl FrameSelector for WhileLost {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let inner = self.inner.decide(ctx);
        let due =
            ctx.tracking_lost && since_processed(ctx) + TIME_TOLERANCE_SECS >= self.period_secs;
        process_if_due(inner, due)
    }

    fn reset(&mut self) {
        self.inner.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gating::{UncertaintyBudget, UncertaintyBudgetParams};

    /// Frames processed by `s` over `secs` of a 10 Hz camera, lost from
    /// `lost_from` to `lost_until` (s).
    fn processed(s: &mut dyn FrameSelector, secs: f64, lost: (f64, f64)) -> Vec<f64> {
        let mut last = None;
        let mut out = Vec::new();
        for k in 0..(secs * 10.0) as usize {
            let t = k as f64 * 0.1;
            let ctx = FrameContext {
                time_secs: t,
                last_processed_secs: last,
                tracking_lost: t >= lost.0 && t < lost.1,
                ..FrameContext::default()
            };
            if s.decide(&ctx).is_process() {
                last = Some(t);
                out.push(t);
            }
        }
        out
    }

    #[test]
    fn while_lost_a_gated_policy_looks_every_period_and_otherwise_as_it_would() {
        // A budget that nothing exceeds: only the first frame, unless lost.
        let budget = || -> Box<dyn FrameSelector> {
            Box::new(UncertaintyBudget::new(UncertaintyBudgetParams::default()).unwrap())
        };
        let mut plain = budget();
        assert_eq!(processed(plain.as_mut(), 20.0, (5.0, 9.0)), vec![0.0]);
        let mut s = WhileLost::new(budget(), AUTHORS_LOST_PERIOD_SECS).unwrap();
        assert_eq!(s.name(), "while_lost[uncertainty_budget]");
        let times = processed(&mut s, 20.0, (5.0, 9.0));
        // The first frame, then from 5 s every 0.4 s until the tracker is
        // found again at 9 s.
        let expected: Vec<f64> = std::iter::once(0.0)
            .chain((0..10).map(|i| 5.0 + 0.4 * f64::from(i)))
            .collect();
        assert_eq!(times.len(), expected.len(), "{times:?}");
        for (a, b) in times.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-9, "{times:?}");
        }
    }

    #[test]
    fn a_period_must_be_positive() {
        let inner = Box::new(UncertaintyBudget::new(UncertaintyBudgetParams::default()).unwrap());
        assert!(WhileLost::new(inner, 0.0).is_err());
    }
}
