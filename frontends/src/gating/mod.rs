//! Residual-gated frame selection (paper §V-B): policies that read the
//! regressor's predicted residual, and wrappers that guard any policy.
//!
//! * [`ResidualSchedule`]: the authors' on-board rule, a processing period
//!   that shrinks quadratically with the predicted residual;
//! * [`UncertaintyBudget`]: process when the odometry drift expected since
//!   the last processed frame exceeds a budget;
//! * [`MaxGap`]: a guard that processes a frame when too long or too far
//!   has passed, composable with any policy;
//! * [`Hysteresis`]: switches to a fast fixed period when the residual
//!   crosses a high threshold and back only below a lower one;
//! * [`FrontLoaded`]: a fixed schedule, dense early and sparse late (the
//!   control of an online learner);
//! * [`Planned`]: processes a precomputed set of frames (the offline
//!   oracle's plan, or a replayed schedule);
//! * [`RescaleKeyframes`]: the authors' keyframe rescaling around any
//!   policy (a property of a scheme's back end);
//! * [`WhileLost`]: while tracking is lost, a frame every 0.4 s (the
//!   authors' 2.5 fps stream), around every gated policy of a scheme.

mod front_loaded;
mod hysteresis;
mod max_gap;
mod planned;
mod rescale_keyframes;
mod residual_schedule;
mod uncertainty_budget;
mod while_lost;

pub use front_loaded::{FrontLoaded, FrontLoadedParams};
pub use hysteresis::{Hysteresis, HysteresisParams};
pub use max_gap::{MaxGap, MaxGapParams};
pub use planned::Planned;
pub use rescale_keyframes::RescaleKeyframes;
pub use residual_schedule::{ResidualSchedule, ResidualScheduleParams};
pub use uncertainty_budget::{UncertaintyBudget, UncertaintyBudgetParams};
pub use while_lost::{AUTHORS_LOST_PERIOD_SECS, WhileLost};

use gpodo_traits::{FrameContext, FrameDecision};
use serde::{Deserialize, Serialize};

/// Which scalar of the predicted residual a policy reads (m/s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResidualSignal {
    /// `‖μ‖`, the norm of the predicted residual mean (the authors').
    #[default]
    Mean,
    /// `√(Σ σ²)`, the predicted residual's standard deviation.
    Std,
    /// `√(‖μ‖² + Σ σ²)`, the root-mean-square error of the odometry.
    Rms,
}

impl ResidualSignal {
    /// The signal's value in `ctx` (m/s).
    pub fn of(self, ctx: &FrameContext) -> f64 {
        let mean_sq: f64 = ctx.residual_mean.iter().map(|m| m * m).sum();
        let var: f64 = ctx.residual_variance.iter().sum();
        match self {
            Self::Mean => mean_sq.sqrt(),
            Self::Std => var.max(0.0).sqrt(),
            Self::Rms => (mean_sq + var.max(0.0)).sqrt(),
        }
    }
}

/// The inner policy's decision, or a frame processed when `due` and the
/// inner policy would skip it: what a guard around a policy returns.
pub(crate) fn process_if_due(inner: FrameDecision, due: bool) -> FrameDecision {
    if inner.is_process() || !due {
        inner
    } else {
        FrameDecision::PROCESS
    }
}

/// Tolerance on frame time stamps when comparing with a period (s).
pub(crate) const TIME_TOLERANCE_SECS: f64 = 1e-3;

/// Seconds since the last processed frame (infinite before the first).
pub(crate) fn since_processed(ctx: &FrameContext) -> f64 {
    ctx.last_processed_secs
        .map_or(f64::INFINITY, |last| ctx.time_secs - last)
}

#[cfg(test)]
pub(crate) mod test_support {
    use gpodo_traits::{FrameContext, FrameSelector};

    /// Runs a selector over frames every 0.1 s for `secs`, with the residual
    /// mean along x given by `residual(t)`, and returns the processed times.
    pub fn run(
        selector: &mut dyn FrameSelector,
        secs: f64,
        residual: impl Fn(f64) -> f64,
    ) -> Vec<f64> {
        let mut last = None;
        let mut processed = Vec::new();
        let mut drift = 0.0;
        let frames = (secs / 0.1).round() as usize;
        for k in 0..frames {
            let t = 0.1 * k as f64;
            let r = residual(t);
            drift += r * r * 0.1;
            let ctx = FrameContext {
                time_secs: t,
                last_processed_secs: last,
                distance_since_processed_m: last.map_or(0.0, |l| 0.04 * (t - l)),
                rotation_since_processed_rad: 0.0,
                residual_mean: vec![r, 0.0, 0.0],
                residual_variance: vec![0.0; 3],
                drift_since_processed: drift,
                drift_variance_since_processed: 0.0,
                tracking_lost: false,
            };
            if selector.decide(&ctx).is_process() {
                processed.push(t);
                last = Some(t);
                drift = 0.0;
            }
        }
        processed
    }
}
