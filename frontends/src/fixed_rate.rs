//! The fixed-rate baseline of Table II: process a frame every `1/fps`
//! seconds whatever the wheels say (ORB-SLAM 2.5 fps and 0.5 fps).
//!
//! The schedule is anchored at the first camera frame it sees, delayed by
//! the phase (0 by default), so the rate does not drift when the camera's
//! frame times are not multiples of the period: a frame is processed when
//! it is the first at or after the next due time (within `tolerance_secs`,
//! for time-stamp jitter). Two phases of one rate process disjoint frames,
//! as many of each, where the camera is fast enough to have them: the
//! comparison's A/A control.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};

use crate::FrontendError;

/// Processes frames at a fixed rate.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedRate {
    period_secs: f64,
    phase_secs: f64,
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
            phase_secs: 0.0,
            tolerance_secs: Self::DEFAULT_TOLERANCE_SECS,
            next_due_secs: None,
            name: format!("fixed_rate[{fps}fps]"),
        })
    }

    /// The same rate with its first frame `phase_secs` after the first
    /// camera frame.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] unless `0 ≤ phase_secs < 1/fps`.
    pub fn with_phase(self, phase_secs: f64) -> Result<Self, FrontendError> {
        if !(phase_secs >= 0.0 && phase_secs < self.period_secs) {
            return Err(FrontendError::InvalidSpec {
                selector: "fixed_rate".into(),
                field: "phase_secs".into(),
                expected: format!(
                    "a delay in [0, {}) s (one period), not {phase_secs}",
                    self.period_secs
                ),
            });
        }
        let name = if phase_secs == 0.0 {
            self.name
        } else {
            format!("{}[phase {phase_secs}s]", self.name)
        };
        Ok(Self {
            phase_secs,
            name,
            ..self
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
            None if self.phase_secs == 0.0 => {
                self.next_due_secs = Some(t + self.period_secs);
                FrameDecision::PROCESS
            }
            None => {
                self.next_due_secs = Some(t + self.phase_secs);
                self.decide(ctx)
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
    fn two_phases_of_one_rate_process_disjoint_frames_as_many_of_each() {
        let times = || (0..600).map(|k| 0.1 * k as f64 + 0.013);
        let a = processed(&mut FixedRate::new(1.0).unwrap(), times());
        let mut shifted = FixedRate::new(1.0).unwrap().with_phase(0.5).unwrap();
        let b = processed(&mut shifted, times());
        assert_eq!((a.len(), b.len()), (60, 60));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!((x - (k as f64 + 0.013)).abs() < 1e-9, "{a:?}");
            assert!((y - (k as f64 + 0.513)).abs() < 1e-9, "{b:?}");
        }
        shifted.reset();
        assert_eq!(processed(&mut shifted, times()), b);
    }

    #[test]
    fn a_phase_of_a_period_or_more_is_rejected_with_the_field_name() {
        for phase in [-0.1, 1.0, f64::NAN] {
            let err = FixedRate::new(1.0).unwrap().with_phase(phase).unwrap_err();
            assert!(err.to_string().contains("phase_secs"), "{err}");
        }
    }

    #[test]
    fn non_positive_rate_is_rejected_with_the_field_name() {
        let err = FixedRate::new(0.0).unwrap_err();
        assert!(err.to_string().contains("fps"), "{err}");
    }
}
