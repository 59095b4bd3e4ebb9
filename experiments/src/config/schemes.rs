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
//!   - label: authors' odometry
//!     odometry: { mean: none, covariance: { absolute: 0 } }
//!     selector: { kind: residual_schedule }
//! ```
//!
//! A scheme's `odometry` names the regressor whose mean corrects the wheel
//! odometry (or `none`) and the one whose prediction sets its covariance
//! (see [`gpodo_frontends::odometry_mode`]); without it, `regressor` does
//! both, with its predictive variance.

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::odometry_mode::{CovarianceSource, OdometryMode};
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

/// How a scheme's wheel odometry uses the trained regressors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SchemeOdometry {
    /// The `regressors` entry whose predicted mean corrects the odometry
    /// (label or index), or `none`: the wheels uncorrected.
    pub mean: MeanRef,
    /// What sets the odometry's velocity covariance.
    pub covariance: CovarianceRef,
}

/// The regressor whose mean corrects the odometry, or none.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum MeanRef {
    /// `none`: the odometry is not corrected.
    Uncorrected(Uncorrected),
    /// A `regressors` entry.
    Regressor(RegressorRef),
}

/// The word `none`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Uncorrected {
    /// No correction.
    None,
}

/// The regressor whose prediction sets the odometry's covariance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum CovarianceRef {
    /// A `regressors` entry's predictive variance.
    Variance(RegressorRef),
    /// An `absolute_regressors` entry (trained on |residual|): its
    /// prediction `â` is the standard deviation, the variance `â²`.
    Absolute(RegressorRef),
    /// The same regressor read as the authors' code does: `â` itself as
    /// the variance (dimensionally inconsistent: m/s taken as (m/s)²).
    AbsoluteAsVariance(RegressorRef),
}

impl CovarianceRef {
    /// The referenced regressor, and whether it is an `absolute_regressors`
    /// entry.
    pub fn regressor(&self) -> (&RegressorRef, bool) {
        match self {
            Self::Variance(r) => (r, false),
            Self::Absolute(r) | Self::AbsoluteAsVariance(r) => (r, true),
        }
    }

    /// The front end's covariance source.
    pub fn source(&self) -> CovarianceSource {
        match self {
            Self::Variance(_) => CovarianceSource::PredictiveVariance,
            Self::Absolute(_) => CovarianceSource::AbsoluteResidual,
            Self::AbsoluteAsVariance(_) => CovarianceSource::AbsoluteResidualAsVariance,
        }
    }
}

/// A scheme's odometry resolved to regressor indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResolvedOdometry {
    /// The `regressors` entry whose mean corrects the odometry, if any.
    pub mean: Option<usize>,
    /// The `regressors` entry whose variance sets the covariance, or
    /// (`absolute`) the `absolute_regressors` entry whose |residual| does.
    pub covariance: usize,
    /// Whether `covariance` indexes `absolute_regressors`.
    pub absolute: bool,
    /// The front end's mode.
    pub mode: OdometryMode,
}

/// The label reports give an `absolute_regressors` entry.
pub fn absolute_label(spec: &RegressorSpec) -> String {
    format!("|residual| {}", spec.label())
}

/// The index of `r` among `labels`.
///
/// # Errors
/// What is wrong with the reference, and what would be accepted (`list`
/// names the list).
fn resolve(r: &RegressorRef, labels: &[String], list: &str) -> Result<usize, (String, String)> {
    match r {
        RegressorRef::Index(i) if *i < labels.len() => Ok(*i),
        RegressorRef::Index(i) => Err((
            format!("regressor index {i} out of range"),
            format!("an index into `{list}` (0..{})", labels.len()),
        )),
        RegressorRef::Label(l) => labels.iter().position(|x| x == l).ok_or_else(|| {
            (
                format!("unknown regressor `{l}`"),
                format!(
                    "one of `{list}`: {}",
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
    /// Learn in batches of VO targets spanning this many seconds (learners
    /// that learn in batches: the streaming sparse GP); omitted, one online
    /// `update` per target, batched by the regressor's own row count.
    /// Exclusive with `refit_every`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub batch_secs: Option<f64>,
    /// Fewest targets before the first refit or the first batch
    /// (default 20).
    #[serde(default = "default_min_targets")]
    pub min_targets: usize,
    /// Whether the learned mean corrects the odometry (default true);
    /// false keeps the odometry uncorrected and gates frames by the
    /// learned variance alone (a control that separates the two).
    #[serde(default = "default_true", skip_serializing_if = "is_true")]
    pub correct_mean: bool,
}

fn default_true() -> bool {
    true
}

fn is_true(value: &bool) -> bool {
    *value
}

fn default_min_targets() -> usize {
    20
}

impl OnlineSpec {
    /// The learning mode.
    ///
    /// # Errors
    /// The field at fault and what was expected, when both `refit_every`
    /// and `batch_secs` are given.
    pub fn mode(&self) -> Result<OnlineMode, (String, String)> {
        match (self.refit_every, self.batch_secs) {
            (Some(_), Some(_)) => Err((
                "online.batch_secs".into(),
                "either `refit_every` or `batch_secs`, not both".into(),
            )),
            (Some(every), None) => Ok(OnlineMode::Refit {
                every,
                min_targets: self.min_targets,
            }),
            (None, Some(secs)) => Ok(OnlineMode::Batch {
                secs,
                min_targets: self.min_targets,
            }),
            (None, None) => Ok(OnlineMode::Update),
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
    /// Which regressors correct the odometry's mean and set its
    /// covariance; omitted, `regressor` does both (its predictive
    /// variance). Not with `regressor` or `online`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub odometry: Option<SchemeOdometry>,
}

impl SchemeSpec {
    /// The scheme's back end, as the reports compare it: its tracking
    /// prior (`default_prior` when the scheme sets none) and where its
    /// residuals come from (a trained regressor's label from
    /// `regressor_labels`, or the online regressor), and the keyframe
    /// rescaling when it has one. Fixed-rate controls and a gated scheme
    /// are comparable when their back ends are equal.
    pub fn back_end(&self, config: &super::ExperimentConfig) -> String {
        let prior = self.motion_prior.unwrap_or(config.frontend.motion_prior);
        let residuals = self.back_end_residuals(config);
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

    /// Where the scheme's residuals come from, as the reports name it: the
    /// online regressor, the trained regressor, or the odometry's mean and
    /// covariance regressors.
    pub fn back_end_residuals(&self, config: &super::ExperimentConfig) -> String {
        let regressor_labels = &config.regressor_labels();
        let absolute_labels = &config.absolute_regressor_labels();
        let name = |labels: &[String], r: &RegressorRef| match r {
            RegressorRef::Index(i) => labels.get(*i).cloned().unwrap_or_else(|| format!("#{i}")),
            RegressorRef::Label(l) => l.clone(),
        };
        match (&self.online, &self.odometry) {
            (Some(online), _) => format!("online {}", online.regressor.label()),
            (None, None) => self
                .regressor_index(regressor_labels)
                .ok()
                .and_then(|i| regressor_labels.get(i).cloned())
                .unwrap_or_else(|| "unknown regressor".into()),
            (None, Some(o)) => {
                let mean = match &o.mean {
                    MeanRef::Uncorrected(_) => "uncorrected odometry".to_string(),
                    MeanRef::Regressor(r) => format!("mean of {}", name(regressor_labels, r)),
                };
                let covariance = match &o.covariance {
                    CovarianceRef::Variance(r) => {
                        format!("variance of {}", name(regressor_labels, r))
                    }
                    CovarianceRef::Absolute(r) => format!("σ = {}", name(absolute_labels, r)),
                    CovarianceRef::AbsoluteAsVariance(r) => {
                        format!("σ² = {}", name(absolute_labels, r))
                    }
                };
                format!("{mean}, {covariance}")
            }
        }
    }

    /// The scheme's odometry: which `regressors` entry corrects the mean,
    /// which entry (of `labels` or `absolute_labels`) sets the covariance,
    /// and the front end's mode. Without `odometry`, the scheme's
    /// `regressor` does both with its predictive variance; an online
    /// scheme has no trained regressor and gets `None`.
    ///
    /// # Errors
    /// The offending field (below `odometry`, or `regressor`), what is
    /// wrong and what would be accepted.
    pub fn resolve_odometry(
        &self,
        labels: &[String],
        absolute_labels: &[String],
    ) -> Result<Option<ResolvedOdometry>, (&'static str, String, String)> {
        if self.online.is_some() {
            return Ok(None);
        }
        let Some(odometry) = &self.odometry else {
            let r = self
                .regressor_index(labels)
                .map_err(|(p, e)| ("regressor", p, e))?;
            return Ok(Some(ResolvedOdometry {
                mean: Some(r),
                covariance: r,
                absolute: false,
                mode: OdometryMode::CORRECTED,
            }));
        };
        let mean = match &odometry.mean {
            MeanRef::Uncorrected(_) => None,
            MeanRef::Regressor(r) => {
                Some(resolve(r, labels, "regressors").map_err(|(p, e)| ("odometry.mean", p, e))?)
            }
        };
        let (r, absolute) = odometry.covariance.regressor();
        let field = match &odometry.covariance {
            CovarianceRef::Variance(_) => "odometry.covariance.variance",
            CovarianceRef::Absolute(_) => "odometry.covariance.absolute",
            CovarianceRef::AbsoluteAsVariance(_) => "odometry.covariance.absolute_as_variance",
        };
        let covariance = if absolute {
            resolve(r, absolute_labels, "absolute_regressors")
        } else {
            resolve(r, labels, "regressors")
        }
        .map_err(|(p, e)| (field, p, e))?;
        Ok(Some(ResolvedOdometry {
            mean,
            covariance,
            absolute,
            mode: OdometryMode {
                correct_mean: mean.is_some(),
                covariance: odometry.covariance.source(),
            },
        }))
    }

    /// The index of the scheme's trained regressor among `labels`.
    ///
    /// # Errors
    /// What is wrong with the reference, and what would be accepted.
    pub fn regressor_index(&self, labels: &[String]) -> Result<usize, (String, String)> {
        match &self.regressor {
            None => Ok(0),
            Some(r) => resolve(r, labels, "regressors"),
        }
    }
}
