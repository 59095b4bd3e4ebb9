//! The front end's settings, as written under `frontend:` in an experiment
//! file. Every field has a documented default.

use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::backend::BackendParams;
use crate::odometry::OdometryNoise;
use crate::vo::stereo::StereoVoParams;
use crate::vo::{ReplayVoParams, SimulatedVoParams};

/// Which visual odometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum VoSpec {
    /// The feature tracker simulated from ground truth (default).
    Simulated(SimulatedVoParams),
    /// A VO log replayed.
    Replay(ReplayVoParams),
    /// The stereo VO on the camera's images (the rendered camera of a
    /// simulated testbed).
    Stereo(StereoVoParams),
}

impl Default for VoSpec {
    fn default() -> Self {
        Self::Simulated(SimulatedVoParams::default())
    }
}

/// The motion prior a frame is tracked with (§V-B: "an initial guess
/// between two consecutive image frames").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionPrior {
    /// Wheel odometry (corrected by the predicted residual) since the last
    /// processed frame (default).
    #[default]
    Odometry,
    /// The last visual-odometry velocity, extrapolated over the gap
    /// (ORB-SLAM's constant-velocity model).
    ConstantVelocity,
    /// No prior: frames are matched against the reference keyframe alone.
    None,
}

/// When a tracked frame becomes a keyframe (ORB-SLAM inserts one when the
/// current frame tracks too few of its reference keyframe's points).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KeyframeParams {
    /// A tracked frame whose overlap with its reference keyframe is below
    /// this becomes a keyframe (default 0.8). A selector's
    /// `keyframe_threshold_scale` `s` moves the threshold to
    /// `1 − (1 − min_overlap)·s`: below 1, keyframes come sooner.
    pub min_overlap: f64,
    /// A tracked frame this long after the reference keyframe becomes a
    /// keyframe whatever its overlap (s; default off).
    pub max_interval_secs: Option<f64>,
}

impl Default for KeyframeParams {
    fn default() -> Self {
        Self {
            min_overlap: 0.8,
            max_interval_secs: None,
        }
    }
}

/// Loop closing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopClosureParams {
    /// Look for loops when a keyframe is inserted (default true).
    pub enabled: bool,
    /// Only keyframes at least this much older are loop candidates
    /// (s; default 60).
    pub min_separation_secs: f64,
}

impl Default for LoopClosureParams {
    fn default() -> Self {
        Self {
            enabled: true,
            min_separation_secs: 60.0,
        }
    }
}

/// The compute model of a run: `frames × frame_ms + keyframes ×
/// keyframe_ms`, deterministic, calibrated against gpodo's stereo VO on
/// the rendered camera on one core (`cargo bench -p gpodo-experiments
/// --bench stereo_vo`; `bench/README.md`, "The camera and the stereo VO").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ComputeCost {
    /// Cost of processing one frame: ORB on both images of a 512 × 384
    /// pair and their row matches, then tracking (ms; default 28, the
    /// stereo VO's 27.1 + 0.8 ms on gravel; 21 ms on compact soil).
    pub frame_ms: f64,
    /// Extra cost of a keyframe: the stereo VO's loop-closure query against
    /// the earlier keyframes (ms; default 5, against 80 of them). The
    /// stereo VO runs no local bundle adjustment, which in ORB-SLAM2 makes
    /// a keyframe cost far more; set it for such a back end.
    pub keyframe_ms: f64,
}

impl Default for ComputeCost {
    fn default() -> Self {
        Self {
            frame_ms: 28.0,
            keyframe_ms: 5.0,
        }
    }
}

/// Online learning from visual odometry (§VI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnlineTargetParams {
    /// A VO residual target spans at least this long an interval (s;
    /// default 4): longer intervals average the VO noise down (on the
    /// simulated testbed the VO noise of 2-s targets exceeded the residual
    /// itself).
    pub min_interval_secs: f64,
    /// Intervals longer than this (a loss in between) give no target
    /// (s; default 12).
    pub max_interval_secs: f64,
}

impl Default for OnlineTargetParams {
    fn default() -> Self {
        Self {
            min_interval_secs: 4.0,
            max_interval_secs: 12.0,
        }
    }
}

/// Everything the front end is configured with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrontendParams {
    /// The visual odometry (default simulated).
    pub vo: VoSpec,
    /// The tracking prior (default odometry).
    pub motion_prior: MotionPrior,
    /// Keyframe insertion.
    pub keyframes: KeyframeParams,
    /// Loop closing.
    pub loop_closure: LoopClosureParams,
    /// Odometry noise beyond the predicted residual.
    pub odometry: OdometryNoise,
    /// Residual variance per axis before the first prediction arrives, and
    /// of an online model that has seen nothing ((m/s)²; default 1e-4).
    pub initial_residual_variance: f64,
    /// The pose-graph optimisation.
    pub backend: BackendParams,
    /// The compute proxy.
    pub cost: ComputeCost,
    /// Online learning targets.
    pub online: OnlineTargetParams,
    /// While tracking is lost, every gated policy processes a frame this
    /// often (s; default 0.4, the authors' 2.5 fps stream; null: the
    /// policy alone decides). Fixed-rate baselines keep their rate.
    pub lost_frame_period_secs: Option<f64>,
    /// How the odometry uses the residual predictions: set per scheme (a
    /// scheme's `odometry`), not in the experiment's `frontend` section.
    #[serde(skip)]
    pub odometry_mode: crate::odometry_mode::OdometryMode,
}

impl Default for FrontendParams {
    fn default() -> Self {
        Self {
            vo: VoSpec::default(),
            motion_prior: MotionPrior::default(),
            keyframes: KeyframeParams::default(),
            loop_closure: LoopClosureParams::default(),
            odometry: OdometryNoise::default(),
            initial_residual_variance: 1e-4,
            backend: BackendParams::default(),
            cost: ComputeCost::default(),
            online: OnlineTargetParams::default(),
            lost_frame_period_secs: Some(crate::gating::AUTHORS_LOST_PERIOD_SECS),
            odometry_mode: crate::odometry_mode::OdometryMode::default(),
        }
    }
}

impl FrontendParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidConfig {
                field: field.into(),
                expected: expected.into(),
            })
        };
        match &self.vo {
            VoSpec::Simulated(p) => p.validate()?,
            VoSpec::Replay(p) => p.validate()?,
            VoSpec::Stereo(p) => p.validate()?,
        }
        let k = &self.keyframes;
        if !(k.min_overlap.is_finite() && (0.0..=1.0).contains(&k.min_overlap)) {
            return bad("keyframes.min_overlap", "a fraction in [0, 1]");
        }
        if let Some(v) = k.max_interval_secs
            && !(v.is_finite() && v > 0.0)
        {
            return bad(
                "keyframes.max_interval_secs",
                "a positive duration, or null",
            );
        }
        if !(self.loop_closure.min_separation_secs.is_finite()
            && self.loop_closure.min_separation_secs >= 0.0)
        {
            return bad(
                "loop_closure.min_separation_secs",
                "a non-negative duration",
            );
        }
        let o = &self.odometry;
        if !(o.translation_m2_per_s.is_finite() && o.translation_m2_per_s > 0.0) {
            return bad("odometry.translation_m2_per_s", "a positive variance rate");
        }
        if !(o.rotation_rad2_per_s.is_finite() && o.rotation_rad2_per_s > 0.0) {
            return bad("odometry.rotation_rad2_per_s", "a positive variance rate");
        }
        if let Some(b) = o.rotation_bias_radps
            && !(b.is_finite() && b >= 0.0)
        {
            return bad(
                "odometry.rotation_bias_radps",
                "a non-negative bias in rad/s, or null",
            );
        }
        if !(self.initial_residual_variance.is_finite() && self.initial_residual_variance > 0.0) {
            return bad("initial_residual_variance", "a positive variance in (m/s)²");
        }
        self.backend.validate()?;
        for (field, v) in [
            ("cost.frame_ms", self.cost.frame_ms),
            ("cost.keyframe_ms", self.cost.keyframe_ms),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(field, "a non-negative cost in ms");
            }
        }
        let t = &self.online;
        if !(t.min_interval_secs.is_finite() && t.min_interval_secs > 0.0) {
            return bad("online.min_interval_secs", "a positive duration");
        }
        if !(t.max_interval_secs.is_finite() && t.max_interval_secs >= t.min_interval_secs) {
            return bad(
                "online.max_interval_secs",
                "a duration at least min_interval_secs",
            );
        }
        if let Some(p) = self.lost_frame_period_secs
            && !(p.is_finite() && p > 0.0)
        {
            return bad("lost_frame_period_secs", "a positive period in s, or null");
        }
        Ok(())
    }
}
