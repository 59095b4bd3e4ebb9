//! The frame selector kinds an experiment may name in YAML, as a closed enum
//! (`kind: fixed_rate`, ...), validated when the configuration is read and
//! built into a runtime `Box<dyn FrameSelector>`. Wrappers nest:
//!
//! ```yaml
//! selector:
//!   kind: max_gap
//!   max_gap_secs: 4
//!   inner: { kind: residual_schedule, r_max_mps: 0.01 }
//! ```

use gpodo_traits::FrameSelector;
use serde::{Deserialize, Serialize};

use crate::gating::{
    FrontLoadedParams, Hysteresis, HysteresisParams, MaxGap, MaxGapParams, ResidualSchedule,
    ResidualScheduleParams, ResidualSignal, UncertaintyBudget, UncertaintyBudgetParams,
};
use crate::odometry_mode::OdometryMode;
use crate::oracle::OracleParams;
use crate::{FixedRate, FrontendError};

fn default_max_gap_secs() -> Option<f64> {
    MaxGapParams::default().max_gap_secs
}

/// A frame selector as written in an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SelectorSpec {
    /// Process frames at a fixed rate (the paper's 2.5 and 0.5 fps).
    FixedRate {
        /// Frames per second.
        fps: f64,
        /// Delay of the first processed frame after the traverse's first
        /// camera frame (s; default 0, in `[0, 1/fps)`): the same rate at
        /// two phases processes disjoint frames, as many of each (the
        /// comparison's A/A control).
        #[serde(default, skip_serializing_if = "is_zero")]
        phase_secs: f64,
    },
    /// The authors' quadratic schedule on the predicted residual.
    ResidualSchedule(ResidualScheduleParams),
    /// Process when the expected odometry drift exceeds a budget.
    UncertaintyBudget(UncertaintyBudgetParams),
    /// A guard around another policy.
    MaxGap {
        /// The guarded policy.
        inner: Box<SelectorSpec>,
        /// Longest time between processed frames (s; default 4; null: off).
        #[serde(default = "default_max_gap_secs")]
        max_gap_secs: Option<f64>,
        /// Longest odometry distance between them (m; default off).
        #[serde(default)]
        max_distance_m: Option<f64>,
        /// Largest odometry rotation between them (rad; default off).
        #[serde(default)]
        max_rotation_rad: Option<f64>,
    },
    /// Two-threshold alert mode around another policy.
    Hysteresis {
        /// The policy outside alert mode.
        inner: Box<SelectorSpec>,
        /// Residual that starts the alert mode (m/s; default 0.008).
        #[serde(default = "HysteresisParams::default_enter")]
        enter_mps: f64,
        /// Residual that ends it (m/s; default 0.004).
        #[serde(default = "HysteresisParams::default_exit")]
        exit_mps: f64,
        /// Period in alert mode (s; default 0.4).
        #[serde(default = "HysteresisParams::default_alert_period")]
        alert_period_secs: f64,
        /// Keyframe threshold scale in alert mode (default 0.5).
        #[serde(default = "HysteresisParams::default_alert_scale")]
        alert_keyframe_scale: f64,
        /// The residual scalar compared (default `mean`).
        #[serde(default)]
        signal: ResidualSignal,
    },
    /// The offline oracle (sees ground truth; planned by the runner).
    Oracle(OracleParams),
    /// A fixed schedule, dense early and sparse late, with the frames of
    /// another scheme (the control of an online learner).
    FrontLoaded(FrontLoadedParams),
}

impl SelectorSpec {
    /// A short label for reports.
    pub fn label(&self) -> String {
        match self {
            Self::FixedRate { fps, phase_secs } if *phase_secs == 0.0 => format!("fixed {fps} fps"),
            Self::FixedRate { fps, phase_secs } => format!("fixed {fps} fps, phase {phase_secs} s"),
            Self::ResidualSchedule(p) => format!(
                "residual schedule (r_max {} m/s, {}–{} s)",
                p.r_max_mps, p.t_cam_secs, p.t_max_secs
            ),
            Self::UncertaintyBudget(p) => {
                format!("uncertainty budget ({:.0} mm)", 1e3 * p.budget_m2.sqrt())
            }
            Self::MaxGap {
                inner,
                max_gap_secs,
                ..
            } => match max_gap_secs {
                Some(g) => format!("{} + max gap {g} s", inner.label()),
                None => format!("{} + max gap", inner.label()),
            },
            Self::Hysteresis {
                inner,
                enter_mps,
                exit_mps,
                ..
            } => format!("{} + hysteresis {exit_mps}/{enter_mps} m/s", inner.label()),
            Self::FrontLoaded(p) => format!(
                "front-loaded ({} fps for {} s, then the frames of {})",
                p.early_fps, p.early_secs, p.same_as
            ),
            Self::Oracle(p) => match (&p.frames, &p.same_as) {
                (Some(n), _) => format!("oracle ({n} frames)"),
                (None, Some(s)) => format!("oracle (frames of {s})"),
                (None, None) => "oracle".into(),
            },
        }
    }

    /// Whether the selector needs the regressor's predictions (every kind
    /// but the fixed rate and the oracle reads them): a gated policy, which
    /// a scheme wraps in [`crate::gating::WhileLost`].
    pub fn reads_residuals(&self) -> bool {
        match self {
            Self::FixedRate { .. } | Self::Oracle(_) | Self::FrontLoaded(_) => false,
            Self::ResidualSchedule(_) | Self::UncertaintyBudget(_) | Self::Hysteresis { .. } => {
                true
            }
            Self::MaxGap { inner, .. } => inner.reads_residuals(),
        }
    }

    /// The scheme whose frames this selector matches (an oracle's or a
    /// front-loaded schedule's `same_as`): the runner runs that one first.
    pub fn same_as(&self) -> Option<&String> {
        match self {
            Self::Oracle(p) => p.same_as.as_ref(),
            Self::FrontLoaded(p) => Some(&p.same_as),
            Self::FixedRate { .. }
            | Self::ResidualSchedule(_)
            | Self::UncertaintyBudget(_)
            | Self::MaxGap { .. }
            | Self::Hysteresis { .. } => None,
        }
    }

    /// Why this selector can run only offline, over a whole recorded
    /// traverse: the oracle plans with the ground truth, and a
    /// front-loaded schedule takes its frame count from another scheme's
    /// run. `None` for a causal selector (one that decides each frame from
    /// what came before it), which may gate a live camera.
    pub fn offline_only(&self) -> Option<&'static str> {
        match self {
            Self::Oracle(_) => {
                Some("the oracle plans its frames with the ground truth of the whole traverse")
            }
            Self::FrontLoaded(_) => Some(
                "a front-loaded schedule takes its frame count from another scheme's run of the whole traverse",
            ),
            Self::MaxGap { inner, .. } | Self::Hysteresis { inner, .. } => inner.offline_only(),
            Self::FixedRate { .. } | Self::ResidualSchedule(_) | Self::UncertaintyBudget(_) => None,
        }
    }

    /// The oracle's settings when this is the oracle.
    pub fn oracle(&self) -> Option<&OracleParams> {
        match self {
            Self::Oracle(p) => Some(p),
            Self::FixedRate { .. }
            | Self::ResidualSchedule(_)
            | Self::UncertaintyBudget(_)
            | Self::MaxGap { .. }
            | Self::Hysteresis { .. }
            | Self::FrontLoaded(_) => None,
        }
    }

    /// The same selector with every drift budget counting the drift of the
    /// odometry `mode` describes: an unset `count_mean` is set, one that
    /// contradicts the mode is an error.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming `count_mean` and the value the
    /// mode implies.
    pub fn for_odometry(&self, mode: &OdometryMode) -> Result<Self, FrontendError> {
        let counts_mean = mode.budget_counts_mean();
        Ok(match self {
            Self::UncertaintyBudget(p) => match p.count_mean {
                Some(c) if c != counts_mean => {
                    return Err(FrontendError::InvalidSpec {
                        selector: "uncertainty_budget".into(),
                        field: "count_mean".into(),
                        expected: format!(
                            "{counts_mean} (or no value) for odometry {}: the budget counts the drift of the odometry the graph uses",
                            mode.label()
                        ),
                    });
                }
                _ => Self::UncertaintyBudget(UncertaintyBudgetParams {
                    count_mean: Some(counts_mean),
                    ..*p
                }),
            },
            Self::MaxGap { .. } | Self::Hysteresis { .. } => {
                let mut wrapper = self.clone();
                if let Self::MaxGap { inner, .. } | Self::Hysteresis { inner, .. } = &mut wrapper {
                    **inner = inner_for_odometry(inner, mode)?;
                }
                wrapper
            }
            // No drift budget inside these.
            Self::FixedRate { .. }
            | Self::ResidualSchedule(_)
            | Self::Oracle(_)
            | Self::FrontLoaded(_) => self.clone(),
        })
    }

    /// Checks every field (nested ones too).
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the selector and field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        match self {
            Self::Oracle(p) => p.validate(),
            Self::FrontLoaded(p) => p.validate(),
            Self::FixedRate { .. }
            | Self::ResidualSchedule(_)
            | Self::UncertaintyBudget(_)
            | Self::MaxGap { .. }
            | Self::Hysteresis { .. } => self.build().map(|_| ()),
        }
    }

    /// Builds the runtime selector.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the bad field; the oracle is
    /// planned by the runner and cannot be built here.
    pub fn build(&self) -> Result<Box<dyn FrameSelector>, FrontendError> {
        Ok(match self {
            Self::FixedRate { fps, phase_secs } => {
                Box::new(FixedRate::new(*fps)?.with_phase(*phase_secs)?)
            }
            Self::ResidualSchedule(p) => Box::new(ResidualSchedule::new(*p)?),
            Self::UncertaintyBudget(p) => Box::new(UncertaintyBudget::new(*p)?),
            Self::MaxGap {
                inner,
                max_gap_secs,
                max_distance_m,
                max_rotation_rad,
            } => Box::new(MaxGap::new(
                inner.build()?,
                MaxGapParams {
                    max_gap_secs: *max_gap_secs,
                    max_distance_m: *max_distance_m,
                    max_rotation_rad: *max_rotation_rad,
                },
            )?),
            Self::Hysteresis {
                inner,
                enter_mps,
                exit_mps,
                alert_period_secs,
                alert_keyframe_scale,
                signal,
            } => Box::new(Hysteresis::new(
                inner.build()?,
                HysteresisParams {
                    enter_mps: *enter_mps,
                    exit_mps: *exit_mps,
                    alert_period_secs: *alert_period_secs,
                    alert_keyframe_scale: *alert_keyframe_scale,
                    signal: *signal,
                },
            )?),
            Self::Oracle(_) => {
                return Err(FrontendError::InvalidSpec {
                    selector: "oracle".into(),
                    field: "kind".into(),
                    expected: "a causal selector here; the oracle is planned offline by the runner"
                        .into(),
                });
            }
            Self::FrontLoaded(_) => {
                return Err(FrontendError::InvalidSpec {
                    selector: "front_loaded".into(),
                    field: "kind".into(),
                    expected: "a selector here; a front-loaded schedule takes its frame count from the scheme it matches, in the runner"
                        .into(),
                });
            }
        })
    }
}

/// [`SelectorSpec::for_odometry`] of a wrapper's inner selector, an error
/// naming the field below `inner`.
fn inner_for_odometry(
    inner: &SelectorSpec,
    mode: &OdometryMode,
) -> Result<SelectorSpec, FrontendError> {
    inner.for_odometry(mode).map_err(|e| match e {
        FrontendError::InvalidSpec {
            selector,
            field,
            expected,
        } => FrontendError::InvalidSpec {
            selector,
            field: format!("inner.{field}"),
            expected,
        },
        other => other,
    })
}

/// Whether a default-zero field is left out of the resolved configuration
/// (so that records written before it existed compare equal).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<SelectorSpec, serde_json::Error> {
        serde_json::from_str(json)
    }

    #[test]
    fn every_kind_parses_with_defaults_and_builds() {
        let specs = [
            r#"{"kind": "fixed_rate", "fps": 2.5}"#,
            r#"{"kind": "residual_schedule"}"#,
            r#"{"kind": "uncertainty_budget", "budget_m2": 1e-4}"#,
            r#"{"kind": "max_gap", "inner": {"kind": "residual_schedule"}}"#,
            r#"{"kind": "hysteresis", "inner": {"kind": "fixed_rate", "fps": 0.5}, "enter_mps": 0.01}"#,
        ];
        for json in specs {
            let spec = parse(json).unwrap();
            spec.validate().unwrap();
            let s = spec.build().unwrap();
            assert!(!s.name().is_empty());
        }
        let spec = parse(r#"{"kind": "max_gap", "inner": {"kind": "residual_schedule"}}"#).unwrap();
        assert_eq!(
            spec.label(),
            "residual schedule (r_max 0.01 m/s, 0.4–2 s) + max gap 4 s"
        );
        assert!(spec.reads_residuals());
        assert!(
            !parse(r#"{"kind": "fixed_rate", "fps": 2.5}"#)
                .unwrap()
                .reads_residuals()
        );
    }

    #[test]
    fn unknown_fields_and_kinds_are_rejected() {
        let err = parse(r#"{"kind": "residual_schedule", "rmax": 0.01}"#).unwrap_err();
        assert!(err.to_string().contains("rmax"), "{err}");
        let err = parse(r#"{"kind": "fixed"}"#).unwrap_err();
        assert!(err.to_string().contains("fixed"), "{err}");
        let err =
            parse(r#"{"kind": "max_gap", "inner": {"kind": "fixed_rate", "fsp": 1}}"#).unwrap_err();
        assert!(err.to_string().contains("fsp"), "{err}");
    }

    #[test]
    fn bad_values_name_the_nested_field() {
        let spec = parse(
            r#"{"kind": "max_gap", "inner": {"kind": "residual_schedule", "r_max_mps": -1}}"#,
        )
        .unwrap();
        let err = spec.validate().unwrap_err().to_string();
        assert!(
            err.contains("residual_schedule") && err.contains("r_max_mps"),
            "{err}"
        );
        let spec = parse(r#"{"kind": "oracle"}"#).unwrap();
        assert!(spec.validate().unwrap_err().to_string().contains("same_as"));
        let spec = parse(r#"{"kind": "oracle", "same_as": "GP"}"#).unwrap();
        spec.validate().unwrap();
        assert!(spec.build().is_err());
    }
}
