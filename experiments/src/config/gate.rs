//! The gate file `gpodo live --gate FILE` reads: which policy gates the
//! camera in front of an external stereo VO, what learns online from that
//! VO's poses, and how the node reads the VO. `selector:` and `online:`
//! are written as in an experiment file's schemes.
//!
//! ```yaml
//! selector:
//!   kind: max_gap
//!   max_gap_secs: null
//!   max_rotation_rad: 0.15
//!   max_distance_m: 0.3
//!   inner: { kind: uncertainty_budget, budget_m2: 1.0e-4, count_mean: false }
//! online: { regressor: { kind: ilgr, init_lengthscale: 2.0 } }
//! lost_frame_period_secs: 0.4
//! pairing: { tolerance_secs: 0.0, history_depth: 10 }
//! lost: { silent_secs: 1.0, covariance_at_least: 9999.0, status_topic: /visual_slam/lost }
//! ```
//!
//! Only causal policies can gate a live camera: the oracle and the
//! front-loaded schedule are refused, naming why
//! ([`SelectorSpec::offline_only`]).

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::params::OnlineTargetParams;
use gpodo_node::gate::JumpSettings;
pub use gpodo_node::gate::topics::GateTopics;
use serde::{Deserialize, Serialize};

use crate::config::Issue;
use crate::config::schemes::OnlineSpec;

/// The gate file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GateFile {
    /// The policy that decides per stereo pair (a causal one).
    pub selector: SelectorSpec,
    /// A regressor that learns online from the VO's poses; omitted, the
    /// model given by `--model` is used as saved.
    #[serde(default)]
    pub online: Option<OnlineSpec>,
    /// While the VO is lost, a pair at least this often (s; default 0.4,
    /// the authors' 2.5 fps stream; null: the policy alone), for a policy
    /// that reads the residuals, as the offline schemes do.
    #[serde(default = "default_lost_period")]
    pub lost_frame_period_secs: Option<f64>,
    /// When the residual the policy reads changes (default: `windows`
    /// when the model's rows average a window, else `every_sample`).
    #[serde(default)]
    pub predictions: Option<Predictions>,
    /// The residual variance per axis of a model that knows nothing
    /// ((m/s)²; default 1e-4), which the policy reads until the learner
    /// has learned.
    #[serde(default = "default_initial_variance")]
    pub initial_residual_variance: f64,
    /// How stereo pairs are matched.
    #[serde(default)]
    pub pairing: PairingSpec,
    /// When the VO counts as lost.
    #[serde(default)]
    pub lost: LostSpec,
    /// How long a residual target interval spans.
    #[serde(default)]
    pub targets: OnlineTargetParams,
    /// When a VO pose is a jump, not learned from.
    #[serde(default)]
    pub jump: JumpSettings,
    /// The VO's child frame (`child_frame_id`) in the body frame, when it
    /// is not the body's (the camera's mount, from the rover
    /// description's URDF or measured).
    #[serde(default)]
    pub body_from_child: Option<PoseSpec>,
    /// The VO's `child_frame_id` that `body_from_child` is the transform
    /// of: a pose of another frame is counted and not used (null: not
    /// checked).
    #[serde(default)]
    pub vo_child_frame_id: Option<String>,
    /// The topics.
    #[serde(default)]
    pub topics: GateTopics,
    /// Where and how often the learner's model is written.
    #[serde(default)]
    pub checkpoint: CheckpointSpec,
    /// In a replay (`--replay`), the VO behind the gate: the front end the
    /// offline schemes run (an experiment file's `frontend:`), tracking
    /// the recording imported as `gpodo run` imports it, stepped by the
    /// pairs the gate forwards. Its poses are the body's, so
    /// `body_from_child` must be left out. Omitted: the recording's own
    /// VO topic answers each forwarded pair.
    #[serde(default)]
    pub replay_frontend: Option<gpodo_frontends::params::FrontendParams>,
}

/// When the residual the policy reads changes (a gate file's
/// `predictions:`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Predictions {
    /// At every joint state, predicted on the row the node publishes with
    /// (its trailing window). Each prediction starts a new block of fully
    /// correlated drift, so a policy reading the drift's variance sees
    /// blocks of one sample, far less than offline.
    EverySample,
    /// At the end of each regressor window on the grid from the first
    /// joint state, predicted on that window's row, as Table II's offline
    /// schemes do: the drift's blocks are windows, and a replay makes the
    /// offline decisions. Needs rows averaged over a window.
    Windows,
}

fn default_lost_period() -> Option<f64> {
    Some(gpodo_frontends::gating::AUTHORS_LOST_PERIOD_SECS)
}

fn default_initial_variance() -> f64 {
    1e-4
}

/// How stereo pairs are matched.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PairingSpec {
    /// Largest stamp difference within a pair (s; default 0: exact).
    pub tolerance_secs: f64,
    /// Messages kept per topic while they wait for their partners
    /// (default 10).
    pub history_depth: usize,
}

impl Default for PairingSpec {
    fn default() -> Self {
        Self {
            tolerance_secs: 0.0,
            history_depth: 10,
        }
    }
}

/// When the VO counts as lost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LostSpec {
    /// No pose this long after a forwarded pair (s; default 1; null: off).
    pub silent_secs: Option<f64>,
    /// A position variance at or above this (m²; default 9999, rtabmap's
    /// when lost; null: off).
    pub covariance_at_least: Option<f64>,
    /// A `std_msgs/Bool` topic that is true while the VO is lost
    /// (isaac_ros_visual_slam's status, which keeps a low covariance when
    /// lost, must be wired here); omitted, none.
    pub status_topic: Option<String>,
}

impl Default for LostSpec {
    fn default() -> Self {
        Self {
            silent_secs: Some(1.0),
            covariance_at_least: Some(9999.0),
            status_topic: None,
        }
    }
}

/// A rigid transform.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Translation (m).
    pub translation_m: [f64; 3],
    /// Rotation as a unit quaternion (x, y, z, w).
    pub rotation_xyzw: [f64; 4],
}

/// Where and how often the learner's model is written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CheckpointSpec {
    /// The model file, relative to the gate file's folder (the
    /// `--checkpoint` flag overrides it; neither: no checkpoints).
    pub path: Option<std::path::PathBuf>,
    /// Seconds between checkpoints (default 30).
    pub every_secs: f64,
}

impl Default for CheckpointSpec {
    fn default() -> Self {
        Self {
            path: None,
            every_secs: 30.0,
        }
    }
}

fn positive(path: &str, value: f64, what: &str) -> Result<(), Issue> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Issue::new(path, format!("{value}"), what))
    }
}

impl GateFile {
    /// Checks every field.
    ///
    /// # Errors
    /// An [`Issue`] naming the field's path, what is wrong and what was
    /// expected: an offline-only or invalid selector, an invalid online
    /// learner, or a setting out of range.
    pub fn validate(&self) -> Result<(), Issue> {
        if let Some(why) = self.selector.offline_only() {
            return Err(Issue::new(
                "selector",
                format!(
                    "`{}` cannot gate a live camera: {why}",
                    self.selector.label()
                ),
                "a causal policy: fixed_rate, residual_schedule, uncertainty_budget, or max_gap or hysteresis around one",
            ));
        }
        self.selector
            .validate()
            .map_err(|e| Issue::from_frontend("selector", e))?;
        if let Some(online) = &self.online {
            online
                .regressor
                .validate()
                .map_err(|e| Issue::from_regressor("online.regressor", e))?;
            online.mode().map_err(|(field, expected)| {
                Issue::new(&field, "both `refit_every` and `batch_secs`", expected)
            })?;
            if online.refit_every == Some(0) || online.min_targets == 0 {
                return Err(Issue::new(
                    "online.min_targets",
                    "zero targets",
                    "refit_every and min_targets of at least 1",
                ));
            }
        }
        if let Some(frontend) = &self.replay_frontend {
            frontend.validate().map_err(|e| match e {
                gpodo_frontends::FrontendError::InvalidConfig { field, expected } => Issue::new(
                    &format!("replay_frontend.{field}"),
                    "an invalid setting",
                    expected,
                ),
                e => Issue::from_frontend("replay_frontend", e),
            })?;
            if self.body_from_child.is_some() {
                return Err(Issue::new(
                    "body_from_child",
                    "a transform beside `replay_frontend`",
                    "no `body_from_child`: the replay's front end publishes the body's poses",
                ));
            }
        }
        if let Some(period) = self.lost_frame_period_secs {
            positive(
                "lost_frame_period_secs",
                period,
                "a positive period in s, or null",
            )?;
        }
        positive(
            "initial_residual_variance",
            self.initial_residual_variance,
            "a positive variance in (m/s)²",
        )?;
        let p = &self.pairing;
        if !(p.tolerance_secs.is_finite() && p.tolerance_secs >= 0.0) {
            return Err(Issue::new(
                "pairing.tolerance_secs",
                format!("{}", p.tolerance_secs),
                "a stamp difference of 0 s (exact) or more",
            ));
        }
        if p.history_depth == 0 {
            return Err(Issue::new(
                "pairing.history_depth",
                "0",
                "at least 1 message per topic",
            ));
        }
        if let Some(s) = self.lost.silent_secs {
            positive("lost.silent_secs", s, "a positive time in s, or null")?;
        }
        if let Some(c) = self.lost.covariance_at_least {
            positive(
                "lost.covariance_at_least",
                c,
                "a positive variance in m², or null",
            )?;
        }
        let t = &self.targets;
        positive(
            "targets.min_interval_secs",
            t.min_interval_secs,
            "a positive time in s",
        )?;
        if !(t.max_interval_secs.is_finite() && t.max_interval_secs >= t.min_interval_secs) {
            return Err(Issue::new(
                "targets.max_interval_secs",
                format!("{}", t.max_interval_secs),
                "at least targets.min_interval_secs",
            ));
        }
        positive("jump.max_sigmas", self.jump.max_sigmas, "a positive count")?;
        positive(
            "jump.min_jump_m",
            self.jump.min_jump_m,
            "a positive length in m",
        )?;
        if let Some(pose) = &self.body_from_child {
            let norm = pose.rotation_xyzw.iter().map(|q| q * q).sum::<f64>().sqrt();
            if !((norm - 1.0).abs() < 1e-6 && pose.translation_m.iter().all(|v| v.is_finite())) {
                return Err(Issue::new(
                    "body_from_child.rotation_xyzw",
                    format!("a quaternion of norm {norm}"),
                    "a unit quaternion (x, y, z, w) and a finite translation",
                ));
            }
        }
        positive(
            "checkpoint.every_secs",
            self.checkpoint.every_secs,
            "a positive time in s",
        )
    }
}
