//! The frame selection interface (paper §V-B): decide, frame by frame,
//! whether the visual front-end processes the current camera frame.

use serde::{Deserialize, Serialize};

/// What a selector knows when a camera frame arrives.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FrameContext {
    /// Time stamp of the current camera frame (s).
    pub time_secs: f64,
    /// Time stamp of the last processed frame (s); `None` before the first.
    pub last_processed_secs: Option<f64>,
    /// Path length travelled according to odometry since the last processed
    /// frame (m).
    pub distance_since_processed_m: f64,
    /// Rotation angle according to odometry since the last processed
    /// frame (rad).
    pub rotation_since_processed_rad: f64,
    /// The regressor's latest predicted residual mean per output.
    pub residual_mean: Vec<f64>,
    /// The regressor's latest predicted residual variance per output.
    pub residual_variance: Vec<f64>,
    /// The odometry drift the regressor expects since the last processed
    /// frame: the expected squared displacement error of the odometry,
    /// `Σ_w (‖μ_w‖² + Σ σ²_w) τ_w²` over the regressor windows `w` the rover
    /// spent `τ_w` seconds in (a window's residual error is the same all
    /// through it) (m²).
    pub drift_since_processed: f64,
    /// The same with the variance alone, `Σ_w (Σ σ²_w) τ_w²` (m²): the drift
    /// left when the odometry is corrected by the predicted mean.
    pub drift_variance_since_processed: f64,
    /// Whether visual tracking is lost (the last processed frame was
    /// neither tracked nor relocalised): a policy may look more often
    /// until the tracker has relocalised.
    #[serde(default)]
    pub tracking_lost: bool,
}

/// A selector's decision for one frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum FrameDecision {
    /// Do not process this frame; odometry carries the pose.
    Skip,
    /// Process this frame.
    Process {
        /// Factor applied to the front-end's keyframe thresholds
        /// (1 = unchanged; below 1 inserts keyframes more readily).
        keyframe_threshold_scale: f64,
    },
}

impl FrameDecision {
    /// Process with the front-end's default keyframe thresholds.
    pub const PROCESS: Self = Self::Process {
        keyframe_threshold_scale: 1.0,
    };

    /// Whether the frame is processed.
    pub fn is_process(&self) -> bool {
        matches!(self, Self::Process { .. })
    }
}

/// A frame gating policy.
///
/// Selectors may keep state (a schedule, a hysteresis flag), so `decide`
/// takes `&mut self`; a run owns its selector.
///
/// ```
/// use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
///
/// /// Processes a frame whenever odometry has moved 10 cm.
/// struct EveryTenCentimetres;
///
/// impl FrameSelector for EveryTenCentimetres {
///     fn name(&self) -> &str { "every_10cm" }
///     fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
///         if ctx.last_processed_secs.is_none() || ctx.distance_since_processed_m >= 0.1 {
///             FrameDecision::PROCESS
///         } else {
///             FrameDecision::Skip
///         }
///     }
///     fn reset(&mut self) {}
/// }
///
/// let mut s: Box<dyn FrameSelector> = Box::new(EveryTenCentimetres);
/// let mut ctx = FrameContext { last_processed_secs: Some(0.0), ..Default::default() };
/// assert_eq!(s.decide(&ctx), FrameDecision::Skip);
/// ctx.distance_since_processed_m = 0.12;
/// assert!(s.decide(&ctx).is_process());
/// ```
pub trait FrameSelector: Send {
    /// A short name for reports (e.g. `"fixed_rate[2.5fps]"`).
    fn name(&self) -> &str;

    /// Decides whether the frame described by `ctx` is processed.
    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision;

    /// Forgets all state, as before the first frame of a run.
    fn reset(&mut self);
}
