//! A fixed schedule that looks often at first and rarely later: the
//! control for an online learner (§VI), which looks often while it knows
//! nothing and less once it has learned. It processes a frame every
//! `1 / early_fps` seconds for the first `early_secs` of the traverse and
//! every `1 / late_fps` seconds after, so a learner's gain over it is
//! knowing *where* to look, not looking early. A scheme sets `late_fps` so
//! that the total matches the learner's frames
//! ([`FrontLoadedParams::late_fps_for`]).

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use serde::{Deserialize, Serialize};

use super::{TIME_TOLERANCE_SECS, since_processed};
use crate::FrontendError;

/// The front-loaded control as written in an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrontLoadedParams {
    /// Rate at first (fps; default 2.5, the authors' stream).
    #[serde(default = "FrontLoadedParams::default_early_fps")]
    pub early_fps: f64,
    /// How long the early rate lasts from the first frame (s; default 120).
    #[serde(default = "FrontLoadedParams::default_early_secs")]
    pub early_secs: f64,
    /// The scheme whose frame count on each traverse the schedule matches.
    pub same_as: String,
}

impl FrontLoadedParams {
    fn default_early_fps() -> f64 {
        2.5
    }

    fn default_early_secs() -> f64 {
        120.0
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidSpec {
                selector: "front_loaded".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if !(self.early_fps.is_finite() && self.early_fps > 0.0) {
            return bad("early_fps", "a positive rate in fps");
        }
        if !(self.early_secs.is_finite() && self.early_secs >= 0.0) {
            return bad("early_secs", "a non-negative duration in s");
        }
        if self.same_as.trim().is_empty() {
            return bad("same_as", "the label of the scheme whose frames it matches");
        }
        Ok(())
    }

    /// The late rate that gives `frames` frames over a traverse of
    /// `duration_secs`: what the early phase leaves, spread over the rest
    /// (at least one frame in the late phase).
    pub fn late_fps_for(&self, frames: usize, duration_secs: f64) -> f64 {
        let early_secs = self.early_secs.min(duration_secs);
        let early_frames = (early_secs * self.early_fps).floor() + 1.0;
        let late_secs = (duration_secs - early_secs).max(1e-9);
        ((frames as f64 - early_frames).max(1.0)) / late_secs
    }
}

/// The schedule.
pub struct FrontLoaded {
    early_period_secs: f64,
    early_secs: f64,
    late_period_secs: f64,
    start_secs: Option<f64>,
}

impl FrontLoaded {
    /// `early_fps` for `early_secs` from the first frame, `late_fps` after.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] for a rate that is not positive.
    pub fn new(early_fps: f64, early_secs: f64, late_fps: f64) -> Result<Self, FrontendError> {
        if !(late_fps.is_finite() && late_fps > 0.0) {
            return Err(FrontendError::InvalidSpec {
                selector: "front_loaded".into(),
                field: "same_as".into(),
                expected: "a matched scheme with frames after the early phase".into(),
            });
        }
        FrontLoadedParams {
            early_fps,
            early_secs,
            same_as: "-".into(),
        }
        .validate()?;
        Ok(Self {
            early_period_secs: 1.0 / early_fps,
            early_secs,
            late_period_secs: 1.0 / late_fps,
            start_secs: None,
        })
    }
}

impl FrameSelector for FrontLoaded {
    fn name(&self) -> &str {
        "front_loaded"
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        let start = *self.start_secs.get_or_insert(ctx.time_secs);
        let period = if ctx.time_secs - start < self.early_secs {
            self.early_period_secs
        } else {
            self.late_period_secs
        };
        if since_processed(ctx) + TIME_TOLERANCE_SECS >= period {
            FrameDecision::PROCESS
        } else {
            FrameDecision::Skip
        }
    }

    fn reset(&mut self) {
        self.start_secs = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_early_sparse_late_and_the_total_matches() {
        let params = FrontLoadedParams {
            early_fps: 2.5,
            early_secs: 60.0,
            same_as: "learner".into(),
        };
        // 600 s of a 10 Hz camera, matched to 400 frames.
        let late = params.late_fps_for(400, 600.0);
        let mut s = FrontLoaded::new(2.5, 60.0, late).unwrap();
        let mut last = None;
        let mut times = Vec::new();
        for k in 0..6000 {
            let t = k as f64 * 0.1;
            let ctx = FrameContext {
                time_secs: t,
                last_processed_secs: last,
                ..FrameContext::default()
            };
            if s.decide(&ctx).is_process() {
                last = Some(t);
                times.push(t);
            }
        }
        let early = times.iter().filter(|&&t| t < 60.0).count();
        assert_eq!(early, 150, "2.5 fps for 60 s");
        // The camera grid rounds each late gap up to a frame: within 2 %.
        assert!(
            (times.len() as f64 / 400.0 - 1.0).abs() < 0.02,
            "{}",
            times.len()
        );
    }
}
