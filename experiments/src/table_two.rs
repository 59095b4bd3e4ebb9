//! Table II: every SLAM scheme of the experiment run through the visual
//! front end on every test run. Schemes run in parallel (rayon); each is
//! deterministic, so the table does not depend on the number of threads.
//! Oracle schemes are planned after the scheme whose frame count they
//! match.

use std::path::Path;
use std::time::Instant;

use gpodo_datasets::log::RoverLog;
use gpodo_datasets::residuals::{log_steps, window_rows};
use gpodo_datasets::standardize::Standardizer;
use gpodo_frontends::gating::Planned;
use gpodo_frontends::online::OnlineLearner;
use gpodo_frontends::oracle::{OraclePlan, plan_frames};
use gpodo_frontends::params::VoSpec;
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction, ResidualSource};
use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_frontends::tum::parse_tum;
use gpodo_frontends::vo::{ReplayVo, SimulatedVo, VisualOdometry};
use gpodo_frontends::{FrontendError, FrontendRun, run_frontend};
use gpodo_traits::{FrameSelector, MotionModel, ResidualRegressor, SampleMatrix};
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::config::ExperimentConfig;
use crate::pipeline::PipelineError;
use crate::schemes::SchemeSpec;

/// One scheme on one test run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SchemeResult {
    /// The scheme's label.
    pub label: String,
    /// The test run.
    pub traverse: String,
    /// The selector, as the reports describe it.
    pub selector: String,
    /// Where the residual predictions came from.
    pub residuals: String,
    /// The oracle's plan, for oracle schemes.
    pub oracle: Option<OraclePlanSummary>,
    /// What the front end did and how well.
    pub run: FrontendRun,
    /// Wall-clock time of the run (s).
    pub duration_secs: f64,
}

/// An oracle plan without its frame list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OraclePlanSummary {
    /// Frame budget.
    pub budget: usize,
    /// Frames planned.
    pub planned: usize,
    /// The minimised surrogate cost.
    pub cost: f64,
    /// Candidate frames considered.
    pub candidates: usize,
}

/// Builds the front end's view of a test run: the motion model's twist per
/// step, the regressor windows with inputs standardised like the training
/// rows, the camera frames.
///
/// # Errors
/// [`PipelineError`] when the model fails or the run is inconsistent.
pub fn build_traverse(
    log: &RoverLog,
    model: &dyn MotionModel,
    wheel_radius_m: f64,
    window_secs: f64,
    scaler: &Standardizer,
) -> Result<Traverse, PipelineError> {
    let steps = log_steps(log, model, wheel_radius_m)?;
    let rows = window_rows(&steps, window_secs);
    let d = rows.first().map_or(0, |r| r.inputs.len());
    let raw = SampleMatrix::from_row_major(
        rows.len(),
        d,
        rows.iter().flat_map(|r| r.inputs.iter().copied()).collect(),
    )?;
    let standardised = if rows.is_empty() {
        raw
    } else {
        scaler.transform(&raw)?
    };
    let windows = rows
        .into_iter()
        .enumerate()
        .map(|(i, r)| TraverseWindow {
            start_secs: r.start_secs,
            end_secs: r.end_secs,
            steps: r.steps,
            inputs: standardised.row(i).to_vec(),
            true_residual: r.residual,
        })
        .collect();
    Ok(Traverse::new(
        log.name.clone(),
        log.samples.iter().map(|s| s.time_secs).collect(),
        log.ground_truth.clone(),
        steps.iter().map(|s| s.twist).collect(),
        windows,
        log.camera_times_secs.clone(),
    )?)
}

/// A trained regressor's predictions on every window of a traverse.
///
/// # Errors
/// [`PipelineError::Model`] when prediction fails.
pub fn window_predictions(
    model: &dyn ResidualRegressor,
    traverse: &Traverse,
) -> Result<Vec<ResidualPrediction>, PipelineError> {
    let windows = traverse.windows();
    if windows.is_empty() {
        return Ok(Vec::new());
    }
    let d = windows[0].inputs.len();
    let x = SampleMatrix::from_row_major(
        windows.len(),
        d,
        windows
            .iter()
            .flat_map(|w| w.inputs.iter().copied())
            .collect(),
    )?;
    let p = model.predict(&x)?;
    Ok((0..windows.len())
        .map(|i| ResidualPrediction {
            mean: Vector3::from_iterator(p.mean.row(i).iter().copied()),
            variance: Vector3::from_iterator(p.variance.row(i).iter().copied()),
        })
        .collect())
}

/// The visual odometry of `config` over `traverse`.
fn build_vo(
    config: &ExperimentConfig,
    base: &Path,
    traverse: &Traverse,
) -> Result<Box<dyn VisualOdometry>, PipelineError> {
    Ok(match &config.frontend.vo {
        VoSpec::Simulated(p) => Box::new(SimulatedVo::new(*p, traverse)?),
        VoSpec::Replay(p) => {
            let path = if p.path.is_absolute() {
                p.path.clone()
            } else {
                base.join(&p.path)
            };
            let text = std::fs::read_to_string(&path).map_err(|e| FrontendError::Parse {
                path: path.display().to_string(),
                line: 0,
                detail: format!("cannot read the VO log: {e}"),
            })?;
            let log = parse_tum(&text, &path.display().to_string())?;
            Box::new(ReplayVo::new(p.clone(), traverse, &log)?)
        }
    })
}

/// Everything a scheme needs that is shared between schemes.
pub struct SchemeInputs<'a> {
    /// The experiment.
    pub config: &'a ExperimentConfig,
    /// Its folder (relative paths).
    pub base: &'a Path,
    /// The test runs.
    pub traverses: &'a [Traverse],
    /// Each trained regressor's predictions on each traverse
    /// (`[regressor][traverse]`), for the regressors schemes use.
    pub predictions: &'a [Option<Vec<Vec<ResidualPrediction>>>],
    /// The trained regressors' labels.
    pub regressor_labels: &'a [String],
}

impl SchemeInputs<'_> {
    /// The label and window predictions on traverse `t` of the trained
    /// regressor `scheme` names.
    fn trained_predictions(
        &self,
        scheme: &SchemeSpec,
        t: usize,
    ) -> Result<(String, Vec<ResidualPrediction>), PipelineError> {
        let r = scheme
            .regressor_index(self.regressor_labels)
            .map_err(|(problem, expected)| {
                PipelineError::Inconsistent(format!("{problem}; expected {expected}"))
            })?;
        let predictions = self.predictions[r]
            .as_ref()
            .and_then(|p| p.get(t))
            .cloned()
            .ok_or_else(|| {
                PipelineError::Inconsistent(format!("no predictions of regressor {r}"))
            })?;
        Ok((self.regressor_labels[r].clone(), predictions))
    }

    fn source(
        &self,
        scheme: &SchemeSpec,
        t: usize,
    ) -> Result<(Box<dyn ResidualSource>, String), PipelineError> {
        if let Some(online) = &scheme.online {
            let label = format!("online: {}", online.regressor.label());
            let learner = OnlineLearner::new(
                label.clone(),
                online.regressor.build()?,
                online.mode(),
                self.config.frontend.initial_residual_variance,
            )?;
            return Ok((Box::new(learner), label));
        }
        let (label, predictions) = self.trained_predictions(scheme, t)?;
        Ok((
            Box::new(Precomputed::new(label.clone(), predictions)),
            label,
        ))
    }

    fn run(
        &self,
        scheme: &SchemeSpec,
        t: usize,
        selector: &mut dyn FrameSelector,
        oracle: Option<OraclePlanSummary>,
    ) -> Result<SchemeResult, PipelineError> {
        let start = Instant::now();
        let traverse = &self.traverses[t];
        let (mut source, residuals) = self.source(scheme, t)?;
        let mut vo = build_vo(self.config, self.base, traverse)?;
        let mut frontend = self.config.frontend.clone();
        if let Some(prior) = scheme.motion_prior {
            frontend.motion_prior = prior;
        }
        let run = run_frontend(traverse, &frontend, selector, source.as_mut(), vo.as_mut())?;
        tracing::info!(
            scheme = %scheme.label,
            traverse = traverse.name(),
            frames = run.frames,
            keyframes = run.keyframes,
            rmse_m = run.metrics.rmse_m,
            "scheme done"
        );
        Ok(SchemeResult {
            label: scheme.label.clone(),
            traverse: traverse.name().to_string(),
            selector: scheme.selector.label(),
            residuals,
            oracle,
            run,
            duration_secs: start.elapsed().as_secs_f64(),
        })
    }

    fn run_causal(&self, scheme: &SchemeSpec, t: usize) -> Result<SchemeResult, PipelineError> {
        let mut selector = scheme.selector.build()?;
        self.run(scheme, t, selector.as_mut(), None)
    }

    fn run_oracle(
        &self,
        scheme: &SchemeSpec,
        t: usize,
        done: &[SchemeResult],
    ) -> Result<SchemeResult, PipelineError> {
        let Some(params) = scheme.selector.oracle() else {
            return self.run_causal(scheme, t);
        };
        let traverse = &self.traverses[t];
        let budget = match (&params.frames, &params.same_as) {
            (Some(n), _) => *n,
            (None, Some(other)) => done
                .iter()
                .find(|r| &r.label == other && r.traverse == traverse.name())
                .map(|r| r.run.frames)
                .ok_or_else(|| {
                    PipelineError::Inconsistent(format!(
                        "oracle `{}`: no result of `{other}`",
                        scheme.label
                    ))
                })?,
            (None, None) => 0,
        };
        let (_, predictions) = self.trained_predictions(scheme, t)?;
        let vo = build_vo(self.config, self.base, traverse)?;
        let plan: OraclePlan = plan_frames(
            traverse,
            &predictions,
            vo.as_ref(),
            scheme
                .motion_prior
                .unwrap_or(self.config.frontend.motion_prior),
            params,
            budget,
        )?;
        let summary = OraclePlanSummary {
            budget,
            planned: plan.frames.len(),
            cost: plan.cost,
            candidates: plan.candidates,
        };
        let mut selector = Planned::new("oracle", plan.times_secs);
        self.run(scheme, t, &mut selector, Some(summary))
    }
}

/// Runs every scheme on every traverse: causal schemes in parallel, then
/// the oracles. Results are in (traverse, scheme) order.
///
/// # Errors
/// The first failure, with the scheme it came from.
pub fn run_schemes(inputs: &SchemeInputs<'_>) -> Result<Vec<SchemeResult>, PipelineError> {
    let schemes = &inputs.config.schemes;
    let jobs: Vec<(usize, usize)> = (0..inputs.traverses.len())
        .flat_map(|t| (0..schemes.len()).map(move |s| (t, s)))
        .collect();
    let causal: Vec<(usize, usize)> = jobs
        .iter()
        .copied()
        .filter(|&(_, s)| schemes[s].selector.oracle().is_none())
        .collect();
    let label = |s: usize, e: PipelineError| PipelineError::Scheme {
        label: schemes[s].label.clone(),
        source: Box::new(e),
    };
    let done: Vec<((usize, usize), SchemeResult)> = causal
        .par_iter()
        .map(|&(t, s)| {
            inputs
                .run_causal(&schemes[s], t)
                .map(|r| ((t, s), r))
                .map_err(|e| label(s, e))
        })
        .collect::<Result<_, _>>()?;
    let finished: Vec<SchemeResult> = done.iter().map(|(_, r)| r.clone()).collect();
    let oracles: Vec<((usize, usize), SchemeResult)> = jobs
        .iter()
        .copied()
        .filter(|&(_, s)| schemes[s].selector.oracle().is_some())
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&(t, s)| {
            inputs
                .run_oracle(&schemes[s], t, &finished)
                .map(|r| ((t, s), r))
                .map_err(|e| label(s, e))
        })
        .collect::<Result<_, _>>()?;
    let mut all: Vec<((usize, usize), SchemeResult)> = done.into_iter().chain(oracles).collect();
    all.sort_by_key(|(key, _)| *key);
    Ok(all.into_iter().map(|(_, r)| r).collect())
}
