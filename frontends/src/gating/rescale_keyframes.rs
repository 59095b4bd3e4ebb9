//! The authors' keyframe rescaling as a property of a scheme's back end,
//! apart from its frame selection: whatever policy decides to process a
//! frame, its keyframe threshold is scaled by `T(r) / T_max`, `T(r)` the
//! authors' schedule's period for the predicted residual `r`
//! ([`ResidualSchedule::keyframe_scale`]). Around a fixed rate it gives the
//! control that rescales as the authors' schedule does
//! (`slam-orogen-adaptive_slam`: `scale_keyframes`), so a policy and its
//! fixed-rate control still differ in frame selection only.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};

use super::{ResidualSchedule, ResidualScheduleParams};
use crate::FrontendError;

/// The wrapper.
pub struct RescaleKeyframes {
    inner: Box<dyn FrameSelector>,
    schedule: ResidualSchedule,
    name: String,
}

impl RescaleKeyframes {
    /// Wraps `inner`, rescaling as the schedule `params` would.
    ///
    /// # Errors
    /// As [`ResidualScheduleParams::validate`].
    pub fn new(
        inner: Box<dyn FrameSelector>,
        params: ResidualScheduleParams,
    ) -> Result<Self, FrontendError> {
        let schedule = ResidualSchedule::new(params)?;
        let name = format!("rescale_keyframes[{}]", inner.name());
        Ok(Self {
            inner,
            schedule,
            name,
        })
    }
}

impl FrameSelector for RescaleKeyframes {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        match self.inner.decide(ctx) {
            FrameDecision::Process {
                keyframe_threshold_scale,
            } => FrameDecision::Process {
                keyframe_threshold_scale: keyframe_threshold_scale
                    * self.schedule.keyframe_scale(ctx),
            },
            FrameDecision::Skip => FrameDecision::Skip,
        }
    }

    fn reset(&mut self) {
        self.inner.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FixedRate;

    fn decide(s: &mut dyn FrameSelector, r: f64) -> FrameDecision {
        s.decide(&FrameContext {
            time_secs: 10.0,
            last_processed_secs: Some(0.0),
            residual_mean: vec![r, 0.0, 0.0],
            residual_variance: vec![0.0; 3],
            ..FrameContext::default()
        })
    }

    #[test]
    fn a_fixed_rate_rescales_as_the_authors_schedule_would() {
        let params = ResidualScheduleParams::default();
        let mut s = RescaleKeyframes::new(Box::new(FixedRate::new(0.5).unwrap()), params).unwrap();
        // r = r_max / 2: T = T_max + (T_cam − T_max)/4 = 2 − 0.4 = 1.6 s,
        // so the scale is 1.6 / 2.
        let FrameDecision::Process {
            keyframe_threshold_scale,
        } = decide(&mut s, 0.005)
        else {
            panic!("the fixed rate processes this frame");
        };
        assert!((keyframe_threshold_scale - 0.8).abs() < 1e-12);
        // And the authors' schedule itself, with its own rescaling, agrees.
        let mut authors = ResidualSchedule::new(params).unwrap();
        let FrameDecision::Process {
            keyframe_threshold_scale,
        } = decide(&mut authors, 0.005)
        else {
            panic!("the schedule's 1.6-s period has passed");
        };
        assert!((keyframe_threshold_scale - 0.8).abs() < 1e-12);
    }
}
