//! One SLAM scheme of Table II on one traverse, from its specification to
//! its row: the selector built (or, for the oracle, planned here with
//! hindsight), the visual odometry built from [`VoSpec`], the residual
//! source (a trained regressor's predictions or a regressor learning online
//! from VO), and [`run_frontend`] over the traverse. [`run_scheme`] is the
//! one call an experiment runner makes per scheme and traverse.

use std::sync::Arc;
use std::time::Instant;

use gpodo_traits::{FrameSelector, ResidualRegressor};
use serde::{Deserialize, Serialize};

use crate::gating::{FrontLoaded, Planned, RescaleKeyframes, ResidualScheduleParams, WhileLost};
use crate::hindsight::{SearchSummary, search_frames};
use crate::odometry_mode::OdometryMode;
use crate::online::{OnlineLearner, OnlineMode};
use crate::oracle::plan_frames;
use crate::params::{FrontendParams, MotionPrior, VoSpec};
use crate::prediction::{Precomputed, ResidualPrediction, ResidualSource};
use crate::traverse::Traverse;
use crate::tum::{StampedPose, parse_tum};
use crate::vo::stereo::{StereoFrames, StereoVo};
use crate::vo::{ReplayVo, SimulatedVo, VisualOdometry};
use crate::{FrontendError, FrontendRun, SelectorSpec, run_frontend};

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
    /// The tracking prior the scheme ran with (with `residuals`, its back
    /// end: what fixed-rate and zero-residual controls must share).
    #[serde(default)]
    pub motion_prior: MotionPrior,
    /// How its odometry used the residual predictions.
    #[serde(default)]
    pub odometry: OdometryMode,
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
    /// The hindsight search over the real tracker, when configured.
    #[serde(default)]
    pub search: Option<SearchSummary>,
}

/// Where a scheme's residual predictions come from on one traverse.
pub enum SchemeResiduals {
    /// A regressor trained offline: its predictions on every window.
    Trained {
        /// The regressor's label (reports).
        label: String,
        /// One prediction per window of the traverse.
        predictions: Vec<ResidualPrediction>,
    },
    /// A fresh regressor that learns online from VO targets (§VI).
    Online {
        /// The regressor's label (reports prefix it with `online: `).
        label: String,
        /// The regressor, untrained.
        regressor: Box<dyn ResidualRegressor>,
        /// One update per target, periodic refits, or batches of seconds.
        mode: OnlineMode,
        /// Whether the learned mean corrects the odometry (`false`: only
        /// its variance is used, a control).
        correct_mean: bool,
    },
}

/// One scheme as the runner hands it over.
pub struct SchemeSpecRef<'a> {
    /// The row label.
    pub label: &'a str,
    /// Which frames are processed (an oracle is planned here).
    pub selector: &'a SelectorSpec,
    /// The scheme's tracking prior; `None`, the front end's.
    pub motion_prior: Option<MotionPrior>,
    /// Keyframe thresholds rescaled as this schedule of the authors' would
    /// ([`crate::gating::RescaleKeyframes`]), whatever selects the frames;
    /// `None`, only as the selector says.
    pub rescale_keyframes: Option<&'a ResidualScheduleParams>,
    /// How the scheme's odometry uses the residual predictions.
    pub odometry: OdometryMode,
}

impl<'a> SchemeSpecRef<'a> {
    /// A scheme with the front end's tracking prior, no keyframe
    /// rescaling and gpodo's odometry (the mean corrects, the predictive
    /// variance weights).
    pub fn new(label: &'a str, selector: &'a SelectorSpec) -> Self {
        Self {
            label,
            selector,
            motion_prior: None,
            rescale_keyframes: None,
            odometry: OdometryMode::default(),
        }
    }
}

/// What every scheme on a traverse shares.
#[derive(Clone, Copy)]
pub struct SchemeContext<'a> {
    /// The front end's settings.
    pub params: &'a FrontendParams,
    /// For an oracle matched to another scheme (`same_as`): that scheme's
    /// frames on this traverse.
    pub matched_frames: Option<usize>,
    /// And the times of those frames (s), where the hindsight search
    /// starts.
    pub matched_times: Option<&'a [f64]>,
    /// The visual odometry recorded with this traverse (a bag's `vo`
    /// topic), which a replay without a `path` replays.
    pub recorded_vo: Option<&'a [StampedPose]>,
    /// This traverse's camera frames and their cached features, which the
    /// stereo VO reads (shared by every scheme on the traverse).
    pub frames: Option<&'a Arc<StereoFrames>>,
}

impl VoSpec {
    /// The visual odometry this specification describes over `traverse`;
    /// a replay reads its log's path as given (an experiment file's loader
    /// has made it absolute), and a replay without a path replays
    /// `recorded` (the traverse's own VO).
    ///
    /// # Errors
    /// [`FrontendError::Parse`] naming a VO log that cannot be read or
    /// parsed; [`FrontendError::InvalidConfig`] for a replay without a
    /// path on a traverse recorded without VO, or a stereo VO without
    /// `frames`; what the VO's constructor reports.
    pub fn build(
        &self,
        traverse: &Traverse,
        recorded: Option<&[StampedPose]>,
        frames: Option<&Arc<StereoFrames>>,
    ) -> Result<Box<dyn VisualOdometry>, FrontendError> {
        Ok(match self {
            Self::Stereo(p) => {
                let frames = frames.ok_or_else(|| FrontendError::InvalidConfig {
                    field: "vo.kind".into(),
                    expected: format!(
                        "camera images for `stereo`: test run `{}` has none (the simulated testbed renders them; recordings' image topics are not read yet)",
                        traverse.name()
                    ),
                })?;
                Box::new(StereoVo::new(p.clone(), Arc::clone(frames))?)
            }
            Self::Simulated(p) => Box::new(SimulatedVo::new(*p, traverse)?),
            Self::Replay(p) if p.path.as_os_str().is_empty() => {
                let log = recorded.ok_or_else(|| FrontendError::InvalidConfig {
                    field: "vo.path".into(),
                    expected: format!(
                        "a TUM trajectory file: test run `{}` was recorded without a `vo` topic",
                        traverse.name()
                    ),
                })?;
                Box::new(ReplayVo::new(p.clone(), traverse, log)?)
            }
            Self::Replay(p) => {
                let path = &p.path;
                let text = std::fs::read_to_string(path).map_err(|e| FrontendError::Parse {
                    path: path.display().to_string(),
                    line: 0,
                    detail: format!("cannot read the VO log: {e}"),
                })?;
                let log = parse_tum(&text, &path.display().to_string())?;
                Box::new(ReplayVo::new(p.clone(), traverse, &log)?)
            }
        })
    }

    /// The same odometry with an independent set of random draws: a
    /// simulated tracker reseeded (the key [`FRESH_DRAWS_KEY`] added to
    /// its seed); a replay or a stereo VO, which draw nothing, unchanged. What a search
    /// that saw one set of draws is scored on.
    pub fn with_fresh_draws(&self) -> Self {
        match self {
            Self::Simulated(p) => Self::Simulated(crate::vo::SimulatedVoParams {
                seed: p.seed.wrapping_add(FRESH_DRAWS_KEY),
                ..*p
            }),
            Self::Replay(p) => Self::Replay(p.clone()),
            Self::Stereo(p) => Self::Stereo(p.clone()),
        }
    }
}

/// Added to a simulated tracker's seed for the independent draws a
/// hindsight search is scored on.
pub const FRESH_DRAWS_KEY: u64 = 0x5EED_F2E5_4D2A_3B19;

impl SchemeResiduals {
    /// The source the front end reads, and the label reports show.
    fn into_source(
        self,
        params: &FrontendParams,
        traverse: &Traverse,
    ) -> Result<(Box<dyn ResidualSource>, String), FrontendError> {
        Ok(match self {
            Self::Trained { label, predictions } => (
                Box::new(Precomputed::new(label.clone(), predictions)),
                label,
            ),
            Self::Online {
                label,
                regressor,
                mode,
                correct_mean,
            } => {
                let label = format!("online: {label}");
                let learner = OnlineLearner::new(
                    label.clone(),
                    regressor,
                    mode,
                    params.initial_residual_variance,
                )?
                .with_standardized_inputs(traverse.inputs_standardized())
                .with_mean_correction(correct_mean);
                (Box::new(learner), label)
            }
        })
    }
}

/// The causal selector `spec` describes, as a scheme runs it offline and
/// the live gate runs it: a policy that reads the residuals looks every
/// `lost_frame_period_secs` while tracking is lost ([`WhileLost`]), and
/// keyframe thresholds are rescaled by `rescale_keyframes` when given.
///
/// # Errors
/// [`FrontendError::InvalidSpec`] for a selector only an offline run can
/// build ([`SelectorSpec::offline_only`]) or a bad field; what the
/// wrappers' constructors report.
pub fn causal_selector(
    spec: &SelectorSpec,
    lost_frame_period_secs: Option<f64>,
    rescale_keyframes: Option<&ResidualScheduleParams>,
) -> Result<Box<dyn FrameSelector>, FrontendError> {
    wrap_causal(
        spec.build()?,
        spec,
        lost_frame_period_secs,
        rescale_keyframes,
    )
}

fn wrap_causal(
    mut selector: Box<dyn FrameSelector>,
    spec: &SelectorSpec,
    lost_frame_period_secs: Option<f64>,
    rescale_keyframes: Option<&ResidualScheduleParams>,
) -> Result<Box<dyn FrameSelector>, FrontendError> {
    if let (true, Some(period)) = (spec.reads_residuals(), lost_frame_period_secs) {
        selector = Box::new(WhileLost::new(selector, period)?);
    }
    if let Some(rescale) = rescale_keyframes {
        selector = Box::new(RescaleKeyframes::new(selector, *rescale)?);
    }
    Ok(selector)
}

/// Runs one scheme over one traverse: builds its selector (planning the
/// oracle from the trained predictions and ground truth), its VO and its
/// residual source, and runs the front end.
///
/// # Errors
/// [`FrontendError::InvalidSpec`] for an oracle without trained
/// predictions or without the frames it is matched to; what building the
/// VO, the selector or the online learner, or the run itself, reports.
pub fn run_scheme(
    scheme: &SchemeSpecRef<'_>,
    traverse: &Traverse,
    residuals: SchemeResiduals,
    ctx: &SchemeContext<'_>,
) -> Result<SchemeResult, FrontendError> {
    let start = Instant::now();
    let motion_prior = scheme.motion_prior.unwrap_or(ctx.params.motion_prior);
    let mut frontend = ctx.params.clone();
    frontend.motion_prior = motion_prior;
    frontend.odometry_mode = scheme.odometry;
    let selector_spec = scheme.selector.for_odometry(&scheme.odometry)?;
    let (run, residuals, oracle) = match selector_spec.oracle() {
        None => {
            let mut selector = match &selector_spec {
                SelectorSpec::FrontLoaded(p) => {
                    let frames = ctx
                        .matched_frames
                        .ok_or_else(|| FrontendError::InvalidSpec {
                            selector: "front_loaded".into(),
                            field: "same_as".into(),
                            expected: format!(
                                "the frames of `{}` on `{}` (run that scheme first)",
                                p.same_as,
                                traverse.name()
                            ),
                        })?;
                    let camera = traverse.camera_times_secs();
                    let duration = match (camera.first(), camera.last()) {
                        (Some(a), Some(b)) => b - a,
                        _ => 0.0,
                    };
                    let late = p.late_fps_for(frames, duration);
                    Box::new(FrontLoaded::new(p.early_fps, p.early_secs, late)?)
                }
                spec => spec.build()?,
            };
            selector = wrap_causal(
                selector,
                &selector_spec,
                ctx.params.lost_frame_period_secs,
                scheme.rescale_keyframes,
            )?;
            let (mut source, residuals) = residuals.into_source(ctx.params, traverse)?;
            let mut vo = ctx.params.vo.build(traverse, ctx.recorded_vo, ctx.frames)?;
            let run = run_frontend(
                traverse,
                &frontend,
                selector.as_mut(),
                source.as_mut(),
                vo.as_mut(),
            )?;
            (run, residuals, None)
        }
        Some(params) => {
            let budget = match (&params.frames, &params.same_as) {
                (Some(n), _) => *n,
                (None, Some(other)) => ctx.matched_frames.ok_or_else(|| {
                    oracle_error(format!(
                        "the frames of `{other}` on `{}` (run that scheme first)",
                        traverse.name()
                    ))
                })?,
                (None, None) => 0,
            };
            let SchemeResiduals::Trained { label, predictions } = residuals else {
                return Err(oracle_error(
                    "a trained regressor's predictions (an oracle cannot learn online)".into(),
                ));
            };
            let vo = ctx.params.vo.build(traverse, ctx.recorded_vo, ctx.frames)?;
            let corrections = predictions
                .iter()
                .map(|p| scheme.odometry.window(p).map(|w| w.correction))
                .collect::<Result<Vec<_>, _>>()?;
            let plan = plan_frames(
                traverse,
                &corrections,
                vo.as_ref(),
                motion_prior,
                params,
                budget,
            )?;
            let planned = |times: &[f64]| -> Result<Box<dyn FrameSelector>, FrontendError> {
                let selector: Box<dyn FrameSelector> =
                    Box::new(Planned::new("oracle", times.to_vec()));
                Ok(match scheme.rescale_keyframes {
                    Some(rescale) => Box::new(RescaleKeyframes::new(selector, *rescale)?),
                    None => selector,
                })
            };
            let evaluate = |times: &[f64]| {
                let mut selector = planned(times)?;
                let mut source = Precomputed::new(label.clone(), predictions.clone());
                let mut vo = ctx.params.vo.build(traverse, ctx.recorded_vo, ctx.frames)?;
                run_frontend(
                    traverse,
                    &frontend,
                    selector.as_mut(),
                    &mut source,
                    vo.as_mut(),
                )
            };
            let mut summary = OraclePlanSummary {
                budget,
                planned: plan.frames.len(),
                cost: plan.cost,
                candidates: plan.candidates,
                search: None,
            };
            let run = match &params.search {
                None => evaluate(&plan.times_secs)?,
                Some(search) => {
                    let mut starts = Vec::new();
                    if let Some(times) = ctx.matched_times {
                        starts.push(("matched scheme".to_string(), times.to_vec()));
                    }
                    starts.push(("surrogate plan".to_string(), plan.times_secs.clone()));
                    let found = search_frames(traverse, starts, search, evaluate)?;
                    // The search chose its frames on these tracker draws;
                    // its score comes from an independent set.
                    let mut selector = planned(&found.times_secs)?;
                    let mut source = Precomputed::new(label.clone(), predictions.clone());
                    let mut fresh_vo = ctx.params.vo.with_fresh_draws().build(
                        traverse,
                        ctx.recorded_vo,
                        ctx.frames,
                    )?;
                    let fresh = run_frontend(
                        traverse,
                        &frontend,
                        selector.as_mut(),
                        &mut source,
                        fresh_vo.as_mut(),
                    )?;
                    let mut found_summary = found.summary;
                    found_summary.fresh_draws_rmse_m = Some(fresh.metrics.rmse_m);
                    summary.search = Some(found_summary);
                    fresh
                }
            };
            (run, label, Some(summary))
        }
    };
    tracing::info!(
        scheme = %scheme.label,
        traverse = traverse.name(),
        frames = run.frames,
        keyframes = run.keyframes,
        rmse_m = run.metrics.rmse_m,
        "scheme done"
    );
    Ok(SchemeResult {
        label: scheme.label.to_string(),
        traverse: traverse.name().to_string(),
        selector: scheme.selector.label(),
        residuals,
        motion_prior,
        odometry: scheme.odometry,
        oracle,
        run,
        duration_secs: start.elapsed().as_secs_f64(),
    })
}

fn oracle_error(expected: String) -> FrontendError {
    FrontendError::InvalidSpec {
        selector: "oracle".into(),
        field: "same_as".into(),
        expected,
    }
}
