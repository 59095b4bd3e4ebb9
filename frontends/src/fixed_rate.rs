//! The fixed-rate baseline of Table II: process a frame every `1/fps`
//! seconds whatever the wheels say (ORB-SLAM 2.5 fps and 0.5 fps).
//!
//! The schedule is anchored at the first processed frame, so the rate does
//! not drift when the camera's frame times are not multiples of the period:
//! a frame is processed when it is the first at or after the next due time
//! (within `tolerance_secs`, for time-stamp jitter).

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};

use crate::FrontendError;

/// Processes frames at a fixed rate.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedRate {
    period_secs: f64,
    tolerance_secs: f64,
    next_due_secs: Option<f64>,
    name: String,
}

impl FixedRate {
    /// Default tolerance on time stamps (s).
    pub const DEFAULT_TOLERANCE_SECS: f64 = 1e-3;

    /// A selector processing `fps` frames per second.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] unless `fps` is positive and finite.
    pub fn new(fps: f64) -> Result<Self, FrontendError> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(FrontendError::InvalidSpec {
                selector: "fixed_rate".into(),
                field: "fps".into(),
                expected: "a positive frame rate".into(),
            });
        }
        Ok(Self {
            period_secs: 1.0 / fps,
            tolerance_secs: Self::DEFAULT_TOLERANCE_SECS,
            next_due_secs: None,
            name: format!("fixed_rate[{fps}fps]"),
        })
    }

    /// The processing period (s).
    pub fn period_secs(&self) -> f64 {
        self.period_secs
    }
}

impl FrameSelector for FixedRate {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let t = ctx.time_secs;
        match self.next_due_secs {
            Some(due) if t < due - self.tolerance_secs => FrameDecision::Skip,
            Some(mut due) => {
                while due <= t + self.tolerance_secs {
                    due += self.period_secs;
                }
                self.next_due_secs = Some(due);
                FrameDecision::PROCESS
            }
            None => {
                self.next_due_secs = Some(t + self.period_secs);
                FrameDecision::PROCESS
            }
        }
    }

    fn reset(&mut self) {
        self.next_due_secs = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn processed(selector: &mut FixedRate, times: impl Iterator<Item = f64>) -> Vec<f64> {
        times
            .filter(|&t| {
                selector
                    .decide(&FrameContext {
                        time_secs: t,
                        ..Default::default()
                    })
                    .is_process()
            })
            .collect()
    }

    #[test]
    fn two_and_a_half_fps_on_a_ten_hz_camera_takes_every_fourth_frame() {
        let mut s = FixedRate::new(2.5).unwrap();
        let frames = (0..40).map(|k| 0.1 * k as f64 + 0.013);
        let got = processed(&mut s, frames);
        assert_eq!(got.len(), 10);
        for (k, t) in got.iter().enumerate() {
            assert!((t - (0.4 * k as f64 + 0.013)).abs() < 1e-9, "{got:?}");
        }
    }

    #[test]
    fn half_fps_processes_one_frame_in_twenty_and_does_not_drift() {
        let mut s = FixedRate::new(0.5).unwrap();
        let got = processed(&mut s, (0..10_000).map(|k| 0.1 * k as f64));
        assert_eq!(got.len(), 500);
        assert!((got[499] - 998.0).abs() < 1e-6);
    }

    #[test]
    fn a_gap_in_the_camera_stream_does_not_cause_a_burst() {
        let mut s = FixedRate::new(2.5).unwrap();
        // After the gap, one frame, then back on the grid anchored at 0 s
        // (…, 2.8, 3.2, 3.6): 3.2, not a catch-up burst.
        let times = [0.0, 0.1, 3.0, 3.1, 3.2, 3.3, 3.4];
        assert_eq!(processed(&mut s, times.into_iter()), vec![0.0, 3.0, 3.2]);
    }

    #[test]
    fn reset_restarts_the_schedule() {
        let mut s = FixedRate::new(1.0).unwrap();
        assert_eq!(processed(&mut s, [5.0, 5.5].into_iter()), vec![5.0]);
        s.reset();
        assert_eq!(processed(&mut s, [5.5].into_iter()), vec![5.5]);
    }

    #[test]
    fn non_positive_rate_is_rejected_with_the_field_name() {
        let err = FixedRate::new(0.0).unwrap_err();
        assert!(err.to_string().contains("fps"), "{err}");
    }
}
