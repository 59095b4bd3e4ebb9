//! The authors' on-board rule: with `r` the predicted residual (its mean's
//! norm, or with its variance), the period between processed frames is
//! `T = T_max + (T_cam − T_max)·(r / r_max)²`, clamped to `[T_cam, T_max]`
//! (their values: `T_cam = 0.4 s`, `T_max = 2.0 s`), and the front end's
//! keyframe thresholds are scaled by the same quadratic, `T / T_max`: a
//! large residual makes keyframes denser.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use serde::{Deserialize, Serialize};

use super::{ResidualSignal, TIME_TOLERANCE_SECS, since_processed};
use crate::FrontendError;

/// Settings of [`ResidualSchedule`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ResidualScheduleParams {
    /// Shortest period (s; default 0.4, the authors' `T_cam`).
    pub t_cam_secs: f64,
    /// Longest period (s; default 2.0, the authors' `T_max`).
    pub t_max_secs: f64,
    /// Residual at which the period reaches `T_cam` (m/s; default 0.01).
    pub r_max_mps: f64,
    /// Which scalar of the prediction is `r` (default `mean`).
    pub signal: ResidualSignal,
    /// Scale the keyframe thresholds by `T / T_max` (default true).
    pub scale_keyframes: bool,
}

impl Default for ResidualScheduleParams {
    fn default() -> Self {
        Self {
            t_cam_secs: 0.4,
            t_max_secs: 2.0,
            r_max_mps: 0.01,
            signal: ResidualSignal::Mean,
            scale_keyframes: true,
        }
    }
}

impl ResidualScheduleParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidSpec {
                selector: "residual_schedule".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if !(self.t_cam_secs.is_finite() && self.t_cam_secs > 0.0) {
            return bad("t_cam_secs", "a positive period in s");
        }
        if !(self.t_max_secs.is_finite() && self.t_max_secs >= self.t_cam_secs) {
            return bad("t_max_secs", "a period in s at least t_cam_secs");
        }
        if !(self.r_max_mps.is_finite() && self.r_max_mps > 0.0) {
            return bad("r_max_mps", "a positive residual in m/s");
        }
        Ok(())
    }
}

/// The authors' quadratic schedule.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualSchedule {
    params: ResidualScheduleParams,
}

impl ResidualSchedule {
    /// A schedule with checked settings.
    ///
    /// # Errors
    /// As [`ResidualScheduleParams::validate`].
    pub fn new(params: ResidualScheduleParams) -> Result<Self, FrontendError> {
        params.validate()?;
        Ok(Self { params })
    }

    /// The authors' keyframe threshold scale `T(r) / T_max` for the
    /// residual in `ctx`, whether or not this schedule applies it.
    pub fn keyframe_scale(&self, ctx: &FrameContext) -> f64 {
        self.keyframe_scale_for_period(self.period_secs(self.params.signal.of(ctx)))
    }

    fn keyframe_scale_for_period(&self, period_secs: f64) -> f64 {
        period_secs / self.params.t_max_secs
    }

    /// The period for a residual `r` (m/s).
    pub fn period_secs(&self, r: f64) -> f64 {
        let p = &self.params;
        let x = (r / p.r_max_mps).powi(2);
        (p.t_max_secs + (p.t_cam_secs - p.t_max_secs) * x).clamp(p.t_cam_secs, p.t_max_secs)
    }
}

impl FrameSelector for ResidualSchedule {
    fn name(&self) -> &str {
        "residual_schedule"
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let period = self.period_secs(self.params.signal.of(ctx));
        if since_processed(ctx) + TIME_TOLERANCE_SECS < period {
            return FrameDecision::Skip;
        }
        let scale = if self.params.scale_keyframes {
            self.keyframe_scale_for_period(period)
        } else {
            1.0
        };
        FrameDecision::Process {
            keyframe_threshold_scale: scale,
        }
    }

    fn reset(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::super::test_support::run;
    use super::*;

    #[test]
    fn the_period_is_the_authors_quadratic_clamped() {
        let s = ResidualSchedule::new(ResidualScheduleParams::default()).unwrap();
        assert_eq!(s.period_secs(0.0), 2.0);
        assert!((s.period_secs(0.005) - (2.0 - 1.6 * 0.25)).abs() < 1e-12);
        assert_eq!(s.period_secs(0.01), 0.4);
        assert_eq!(s.period_secs(0.05), 0.4);
    }

    #[test]
    fn large_residuals_process_at_the_camera_period_small_ones_at_t_max() {
        let mut s = ResidualSchedule::new(ResidualScheduleParams::default()).unwrap();
        // First 10 s: residual 0 → every 2 s; then residual ≥ r_max → 0.4 s.
        let times = run(&mut s, 20.0, |t| if t < 10.0 { 0.0 } else { 0.02 });
        let early: Vec<f64> = times.iter().copied().filter(|t| *t < 10.0).collect();
        assert_eq!(early.len(), 5, "{times:?}");
        let late = times.iter().filter(|t| **t >= 10.0).count();
        assert_eq!(late, 25, "{times:?}");
    }

    #[test]
    fn keyframe_thresholds_scale_with_the_period() {
        let mut s = ResidualSchedule::new(ResidualScheduleParams::default()).unwrap();
        let ctx = FrameContext {
            time_secs: 10.0,
            last_processed_secs: Some(0.0),
            residual_mean: vec![0.01, 0.0, 0.0],
            residual_variance: vec![0.0; 3],
            ..Default::default()
        };
        assert_eq!(
            s.decide(&ctx),
            FrameDecision::Process {
                keyframe_threshold_scale: 0.2
            }
        );
    }

    #[test]
    fn the_rms_signal_reads_the_variance_too() {
        let ctx = FrameContext {
            residual_mean: vec![0.003, 0.0, 0.0],
            residual_variance: vec![16e-6, 0.0, 0.0],
            ..Default::default()
        };
        assert!((ResidualSignal::Rms.of(&ctx) - 0.005).abs() < 1e-15);
        assert!((ResidualSignal::Std.of(&ctx) - 0.004).abs() < 1e-15);
        assert!((ResidualSignal::Mean.of(&ctx) - 0.003).abs() < 1e-15);
    }

    #[test]
    fn bad_settings_name_the_field() {
        let err = ResidualSchedule::new(ResidualScheduleParams {
            t_max_secs: 0.1,
            ..Default::default()
        })
        .unwrap_err();
        assert!(err.to_string().contains("t_max_secs"), "{err}");
    }
}
