//! Table II: every SLAM scheme of the experiment run on every test run,
//! one [`run_scheme`] call each, in parallel (rayon). An oracle is planned
//! for the frames of the scheme it is matched to, so those schemes run
//! first; every scheme is deterministic, so the table does not depend on
//! the number of threads or the order.

use gpodo_frontends::odometry_mode::OdometryMode;
use gpodo_frontends::prediction::{AbsolutePrediction, ResidualPrediction};
use gpodo_frontends::scheme::{
    SchemeContext, SchemeResiduals, SchemeResult, SchemeSpecRef, run_scheme,
};
use gpodo_frontends::traverse::Traverse;
use nalgebra::Vector3;
use rayon::prelude::*;

use crate::config::schemes::ResolvedOdometry;
use crate::config::{ExperimentConfig, SchemeSpec};
use crate::error::PipelineError;

/// Everything a scheme needs that is shared between schemes.
pub struct SchemeInputs<'a> {
    /// The experiment.
    pub config: &'a ExperimentConfig,
    /// The test runs.
    pub traverses: &'a [Traverse],
    /// Each trained regressor's predictions on each traverse
    /// (`[regressor][traverse]`), for the regressors schemes use.
    pub predictions: &'a [Option<Vec<Vec<ResidualPrediction>>>],
    /// The trained regressors' labels.
    pub regressor_labels: &'a [String],
    /// Each |residual| regressor's predictions on each traverse
    /// (`[regressor][traverse]`).
    pub absolute_predictions: &'a [Option<Vec<Vec<ResidualPrediction>>>],
    /// The |residual| regressors' labels.
    pub absolute_labels: &'a [String],
    /// Visual odometry recorded with the test runs, by run name.
    pub recorded_vo: &'a std::collections::BTreeMap<String, Vec<gpodo_frontends::tum::StampedPose>>,
    /// Each test run's camera frames, for a VO that reads images.
    pub frames: &'a [Option<std::sync::Arc<gpodo_frontends::vo::stereo::StereoFrames>>],
}

impl SchemeInputs<'_> {
    /// The residual source of `scheme` on traverse `t`: a fresh regressor
    /// learning online, or the trained regressors' window predictions as
    /// the scheme's odometry combines them (the mean of the regressor that
    /// corrects it, or of the one whose variance sets the covariance; the
    /// |residual| regressor's prediction beside them).
    fn residuals(&self, scheme: &SchemeSpec, t: usize) -> Result<SchemeResiduals, PipelineError> {
        if let Some(online) = &scheme.online {
            return Ok(SchemeResiduals::Online {
                label: online.regressor.label(),
                regressor: online.regressor.build()?,
                mode: online.mode().map_err(|(field, expected)| {
                    gpodo_frontends::FrontendError::InvalidConfig { field, expected }
                })?,
                correct_mean: online.correct_mean,
            });
        }
        let resolved = self.odometry(scheme)?;
        let on = |all, r, list| traverse_predictions(all, r, t, list);
        let signed_index = match (resolved.mean, resolved.absolute) {
            (Some(r), _) => Some(r),
            (None, false) => Some(resolved.covariance),
            (None, true) => None,
        };
        let signed = signed_index
            .map(|r| on(self.predictions, r, "regressors"))
            .transpose()?;
        let variance = (!resolved.absolute)
            .then(|| on(self.predictions, resolved.covariance, "regressors"))
            .transpose()?;
        let absolute = resolved
            .absolute
            .then(|| {
                on(
                    self.absolute_predictions,
                    resolved.covariance,
                    "absolute_regressors",
                )
            })
            .transpose()?;
        let windows = self.traverses[t].windows().len();
        let predictions = (0..windows)
            .map(|w| {
                let mean = signed
                    .and_then(|p| p.get(w))
                    .map_or(Vector3::zeros(), |p| p.mean);
                let variance = variance
                    .and_then(|p| p.get(w))
                    .map_or(Vector3::zeros(), |p| p.variance);
                let absolute = absolute.and_then(|p| p.get(w)).map(|p| AbsolutePrediction {
                    mean: p.mean,
                    variance: p.variance,
                });
                ResidualPrediction {
                    mean,
                    variance,
                    absolute,
                }
            })
            .collect();
        let label = match (&scheme.odometry, signed_index) {
            (None, Some(r)) => self.regressor_labels[r].clone(),
            _ => scheme.back_end_residuals(self.config),
        };
        Ok(SchemeResiduals::Trained { label, predictions })
    }

    /// The scheme's odometry, resolved against the experiment's regressors.
    fn odometry(&self, scheme: &SchemeSpec) -> Result<ResolvedOdometry, PipelineError> {
        scheme
            .resolve_odometry(self.regressor_labels, self.absolute_labels)
            .map_err(|(field, problem, expected)| {
                PipelineError::Inconsistent(format!("{field}: {problem}; expected {expected}"))
            })?
            .ok_or_else(|| {
                PipelineError::Inconsistent("an online scheme has no trained odometry".into())
            })
    }

    /// Runs `scheme` on traverse `t`; `done` holds the finished causal
    /// schemes an oracle may be matched to.
    fn run(
        &self,
        scheme: &SchemeSpec,
        t: usize,
        done: &[SchemeResult],
    ) -> Result<SchemeResult, PipelineError> {
        let traverse = &self.traverses[t];
        let matched = scheme.selector.same_as().and_then(|other| {
            done.iter()
                .find(|r| &r.label == other && r.traverse == traverse.name())
        });
        let matched_times: Option<Vec<f64>> =
            matched.map(|r| r.run.processed.iter().map(|p| p.time_secs).collect());
        let ctx = SchemeContext {
            params: &self.config.frontend,
            matched_frames: matched.map(|r| r.run.frames),
            matched_times: matched_times.as_deref(),
            recorded_vo: self.recorded_vo.get(traverse.name()).map(Vec::as_slice),
            frames: self.frames.get(t).and_then(Option::as_ref),
        };
        let spec = SchemeSpecRef {
            label: &scheme.label,
            selector: &scheme.selector,
            motion_prior: scheme.motion_prior,
            rescale_keyframes: scheme.rescale_keyframes.as_ref(),
            odometry: match &scheme.online {
                Some(_) => OdometryMode::CORRECTED,
                None => self.odometry(scheme)?.mode,
            },
        };
        Ok(run_scheme(
            &spec,
            traverse,
            self.residuals(scheme, t)?,
            &ctx,
        )?)
    }
}

/// Regressor `r`'s window predictions on traverse `t` (`list` names the
/// regressor list in the error).
fn traverse_predictions<'p>(
    all: &'p [Option<Vec<Vec<ResidualPrediction>>>],
    r: usize,
    t: usize,
    list: &str,
) -> Result<&'p [ResidualPrediction], PipelineError> {
    all.get(r)
        .and_then(Option::as_ref)
        .and_then(|p| p.get(t))
        .map(Vec::as_slice)
        .ok_or_else(|| PipelineError::Inconsistent(format!("no predictions of {list}[{r}]")))
}

/// Runs every scheme on every traverse, in parallel: first the causal
/// schemes an oracle is matched to, then the oracles beside the other
/// causal schemes (oracles first: a hindsight search is the longest job,
/// and it no longer waits for every causal scheme). Results are in
/// (traverse, scheme) order.
///
/// # Errors
/// The first failure, with the scheme it came from.
pub fn run_schemes(inputs: &SchemeInputs<'_>) -> Result<Vec<SchemeResult>, PipelineError> {
    let schemes = &inputs.config.schemes;
    let jobs: Vec<(usize, usize)> = (0..inputs.traverses.len())
        .flat_map(|t| (0..schemes.len()).map(move |s| (t, s)))
        .collect();
    // Schemes that take another's frames (an oracle, a front-loaded
    // schedule) run after the schemes they match.
    let takes_frames = |s: usize| {
        schemes[s].selector.oracle().is_some() || schemes[s].selector.same_as().is_some()
    };
    let matched: Vec<&String> = schemes
        .iter()
        .filter_map(|s| s.selector.same_as())
        .collect();
    let is_matched = |s: usize| !takes_frames(s) && matched.contains(&&schemes[s].label);
    let label = |s: usize, e: PipelineError| PipelineError::Scheme {
        label: schemes[s].label.clone(),
        source: Box::new(e),
    };
    let run_all = |stage: Vec<(usize, usize)>, done: &[SchemeResult]| {
        stage
            .par_iter()
            .map(|&(t, s)| {
                inputs
                    .run(&schemes[s], t, done)
                    .map(|r| ((t, s), r))
                    .map_err(|e| label(s, e))
            })
            .collect::<Result<Vec<_>, _>>()
    };
    let first = run_all(
        jobs.iter()
            .copied()
            .filter(|&(_, s)| is_matched(s))
            .collect(),
        &[],
    )?;
    let finished: Vec<SchemeResult> = first.iter().map(|(_, r)| r.clone()).collect();
    let rest: Vec<(usize, usize)> = jobs
        .iter()
        .copied()
        .filter(|&(_, s)| takes_frames(s))
        .chain(
            jobs.iter()
                .copied()
                .filter(|&(_, s)| !takes_frames(s) && !is_matched(s)),
        )
        .collect();
    let second = run_all(rest, &finished)?;
    let mut all: Vec<((usize, usize), SchemeResult)> = first.into_iter().chain(second).collect();
    all.sort_by_key(|(key, _)| *key);
    Ok(all.into_iter().map(|(_, r)| r).collect())
}
