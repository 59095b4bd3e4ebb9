//! The SLAM schemes of Table II as written in an experiment file: a frame
//! selector, the regressor whose predictions correct the odometry and feed
//! the selector (trained offline on the training runs), or a fresh
//! regressor that learns online from visual odometry (§VI).
//!
//! ```yaml
//! schemes:
//!   - label: ORB-SLAM 2.5 fps
//!     selector: { kind: fixed_rate, fps: 2.5 }
//!   - label: ORB-SLAM with GP
//!     regressor: "exact GP: rbf"
//!     selector: { kind: residual_schedule }
//!   - label: ILGR online
//!     online: { regressor: { kind: ilgr } }
//!     selector: { kind: uncertainty_budget }
//!   - label: oracle
//!     regressor: "exact GP: rbf"
//!     selector: { kind: oracle, same_as: ORB-SLAM with GP }
//! ```

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::online::OnlineMode;
use gpodo_frontends::params::MotionPrior;
use gpodo_regressors::RegressorSpec;
use serde::{Deserialize, Serialize};

/// Which trained regressor a scheme uses: its index in `regressors` or its
/// report label (`exact GP: rbf`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum RegressorRef {
    /// Position in the experiment's `regressors` list.
    Index(usize),
    /// The regressor's label as the reports print it.
    Label(String),
}

/// A regressor that learns online from visual odometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OnlineSpec {
    /// The regressor (fresh: it sees only VO targets).
    pub regressor: RegressorSpec,
    /// Refit from scratch every this many targets (batch regressors such as
    /// the sparse GP); omitted, one online `update` per target (ILGR).
    #[serde(default)]
    pub refit_every: Option<usize>,
    /// Fewest targets before the first refit (default 20).
    #[serde(default = "default_min_targets")]
    pub min_targets: usize,
}

fn default_min_targets() -> usize {
    20
}

impl OnlineSpec {
    /// The learning mode.
    pub fn mode(&self) -> OnlineMode {
        match self.refit_every {
            Some(every) => OnlineMode::Refit {
                every,
                min_targets: self.min_targets,
            },
            None => OnlineMode::Update,
        }
    }
}

/// One scheme.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SchemeSpec {
    /// The row label.
    pub label: String,
    /// Which frames are processed.
    pub selector: SelectorSpec,
    /// The offline-trained regressor; omitted, the first of `regressors`
    /// (in the paper's experiment, the parametric model alone).
    #[serde(default)]
    pub regressor: Option<RegressorRef>,
    /// Learn online from VO instead of using a trained regressor.
    #[serde(default)]
    pub online: Option<OnlineSpec>,
    /// The tracking prior of this scheme; omitted, `frontend.motion_prior`.
    /// ORB-SLAM alone predicts with a constant-velocity model; the paper's
    /// GP scheme gives the tracker the wheel odometry (§V-B).
    #[serde(default)]
    pub motion_prior: Option<MotionPrior>,
    /// The frames-versus-error curve this scheme is a point of (the same
    /// name on several schemes, each with another value of the policy's
    /// knob); the sweep report draws and tabulates each curve over seeds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<String>,
    /// Rescale the keyframe thresholds as this schedule of the authors'
    /// would (`T(r) / T_max`), whatever selects the frames: part of the
    /// back end, so a rescaled policy is compared with fixed rates that
    /// rescale alike. Omitted, only as the selector says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rescale_keyframes: Option<gpodo_frontends::gating::ResidualScheduleParams>,
}

impl SchemeSpec {
    /// The scheme's back end, as the reports compare it: its tracking
    /// prior (`default_prior` when the scheme sets none) and where its
    /// residuals come from (a trained regressor's label from
    /// `regressor_labels`, or the online regressor), and the keyframe
    /// rescaling when it has one. Fixed-rate controls and a gated scheme
    /// are comparable when their back ends are equal.
    pub fn back_end(&self, default_prior: MotionPrior, regressor_labels: &[String]) -> String {
        let prior = self.motion_prior.unwrap_or(default_prior);
        let residuals = match &self.online {
            Some(online) => format!("online {}", online.regressor.label()),
            None => self
                .regressor_index(regressor_labels)
                .ok()
                .and_then(|i| regressor_labels.get(i).cloned())
                .unwrap_or_else(|| "unknown regressor".into()),
        };
        let prior = match prior {
            MotionPrior::Odometry => "odometry",
            MotionPrior::ConstantVelocity => "constant-velocity",
            MotionPrior::None => "no",
        };
        match &self.rescale_keyframes {
            None => format!("{residuals}, {prior} prior"),
            Some(r) => format!(
                "{residuals}, {prior} prior, keyframes rescaled ({}–{} s)",
                r.t_cam_secs, r.t_max_secs
            ),
        }
    }

    /// The index of the scheme's trained regressor among `labels`.
    ///
    /// # Errors
    /// What is wrong with the reference, and what would be accepted.
    pub fn regressor_index(&self, labels: &[String]) -> Result<usize, (String, String)> {
        match &self.regressor {
            None => Ok(0),
            Some(RegressorRef::Index(i)) if *i < labels.len() => Ok(*i),
            Some(RegressorRef::Index(i)) => Err((
                format!("regressor index {i} out of range"),
                format!("an index into `regressors` (0..{})", labels.len()),
            )),
            Some(RegressorRef::Label(l)) => labels.iter().position(|x| x == l).ok_or_else(|| {
                (
                    format!("unknown regressor `{l}`"),
                    format!(
                        "one of: {}",
                        labels
                            .iter()
                            .map(|x| format!("`{x}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            }),
        }
    }
}
