//! A hysteresis wrapper: the predicted residual (see
//! [`super::ResidualSignal`]) switches the rover into an alert mode when
//! it rises above `enter_mps`, and back to the inner policy only when it
//! falls below `exit_mps < enter_mps`. In alert mode frames are processed
//! at a fixed short period. The two thresholds keep a residual hovering
//! around one threshold from toggling the mode at every prediction.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use serde::{Deserialize, Serialize};

use super::{ResidualSignal, TIME_TOLERANCE_SECS, since_processed};
use crate::FrontendError;

/// Settings of [`Hysteresis`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HysteresisParams {
    /// Residual that starts the alert mode (m/s; default 0.008).
    pub enter_mps: f64,
    /// Residual that ends it (m/s; default 0.004).
    pub exit_mps: f64,
    /// Period of processed frames in alert mode (s; default 0.4).
    pub alert_period_secs: f64,
    /// Keyframe threshold scale in alert mode (default 0.5).
    pub alert_keyframe_scale: f64,
    /// Which scalar of the prediction is compared (default `mean`).
    pub signal: ResidualSignal,
}

impl Default for HysteresisParams {
    fn default() -> Self {
        Self {
            enter_mps: 0.008,
            exit_mps: 0.004,
            alert_period_secs: 0.4,
            alert_keyframe_scale: 0.5,
            signal: ResidualSignal::Mean,
        }
    }
}

impl HysteresisParams {
    /// Default `enter_mps`.
    pub fn default_enter() -> f64 {
        Self::default().enter_mps
    }

    /// Default `exit_mps`.
    pub fn default_exit() -> f64 {
        Self::default().exit_mps
    }

    /// Default `alert_period_secs`.
    pub fn default_alert_period() -> f64 {
        Self::default().alert_period_secs
    }

    /// Default `alert_keyframe_scale`.
    pub fn default_alert_scale() -> f64 {
        Self::default().alert_keyframe_scale
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidSpec {
                selector: "hysteresis".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if !(self.exit_mps.is_finite() && self.exit_mps >= 0.0) {
            return bad("exit_mps", "a non-negative residual in m/s");
        }
        if !(self.enter_mps.is_finite() && self.enter_mps > self.exit_mps) {
            return bad("enter_mps", "a residual in m/s above exit_mps");
        }
        if !(self.alert_period_secs.is_finite() && self.alert_period_secs > 0.0) {
            return bad("alert_period_secs", "a positive period in s");
        }
        if !(self.alert_keyframe_scale.is_finite() && self.alert_keyframe_scale > 0.0) {
            return bad("alert_keyframe_scale", "a positive scale");
        }
        Ok(())
    }
}

/// The wrapper.
pub struct Hysteresis {
    inner: Box<dyn FrameSelector>,
    params: HysteresisParams,
    alert: bool,
    name: String,
}

impl Hysteresis {
    /// Wraps `inner`.
    ///
    /// # Errors
    /// As [`HysteresisParams::validate`].
    pub fn new(
        inner: Box<dyn FrameSelector>,
        params: HysteresisParams,
    ) -> Result<Self, FrontendError> {
        params.validate()?;
        let name = format!("hysteresis[{}]", inner.name());
        Ok(Self {
            inner,
            params,
            alert: false,
            name,
        })
    }

    /// Whether the wrapper is in alert mode.
    pub fn alert(&self) -> bool {
        self.alert
    }
}

impl FrameSelector for Hysteresis {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let r = self.params.signal.of(ctx);
        if !self.alert && r >= self.params.enter_mps {
            self.alert = true;
        } else if self.alert && r <= self.params.exit_mps {
            self.alert = false;
        }
        let inner = self.inner.decide(ctx);
        if !self.alert {
            return inner;
        }
        if since_processed(ctx) + TIME_TOLERANCE_SECS >= self.params.alert_period_secs {
            FrameDecision::Process {
                keyframe_threshold_scale: self.params.alert_keyframe_scale,
            }
        } else {
            FrameDecision::Skip
        }
    }

    fn reset(&mut self) {
        self.alert = false;
        self.inner.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::run;
    use super::*;
    use crate::FixedRate;

    fn slow() -> Box<dyn FrameSelector> {
        Box::new(FixedRate::new(0.25).unwrap())
    }

    #[test]
    fn alert_mode_needs_both_thresholds() {
        let mut s = Hysteresis::new(slow(), HysteresisParams::default()).unwrap();
        // 0–10 s: 0.006 (between thresholds, never entered: slow policy);
        // 10–20 s: 0.009 (enter); 20–30 s: 0.006 (stay alert);
        // 30–40 s: 0.002 (leave).
        let r = |t: f64| match t {
            t if t < 10.0 => 0.006,
            t if t < 20.0 => 0.009,
            t if t < 30.0 => 0.006,
            _ => 0.002,
        };
        let times = run(&mut s, 40.0, r);
        let count = |a: f64, b: f64| times.iter().filter(|t| **t >= a && **t < b).count();
        assert_eq!(count(0.0, 10.0), 3, "{times:?}");
        assert_eq!(count(10.0, 20.0), 25, "{times:?}");
        assert_eq!(count(20.0, 30.0), 25, "{times:?}");
        assert!(count(30.0, 40.0) <= 3, "{times:?}");
        assert!(!s.alert());
    }

    #[test]
    fn enter_must_exceed_exit() {
        let params = HysteresisParams {
            enter_mps: 0.003,
            ..Default::default()
        };
        let err = Hysteresis::new(slow(), params).err().unwrap();
        assert!(err.to_string().contains("enter_mps"), "{err}");
    }
}
