//! Work shared between the runs of a sweep, done once: the data of each
//! distinct dataset specification (simulated or loaded, residual rows,
//! standardisation, test traverses), each regressor trained once per
//! distinct (dataset, regressor) and its predictions on the traverses.
//! Runs then only assemble their results and run their schemes.
//!
//! The stages run one after another, each in parallel over its distinct
//! items: no run waits for another's half-done work.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::traverse::Traverse;
use gpodo_traits::Standardizer;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::config::ExperimentConfig;
use crate::error::PipelineError;
use crate::execute::calibration::{ResidualStatistics, residual_statistics};
use crate::execute::camera::{GroundCell, camera_frames};
use crate::execute::code_version;
use crate::execute::data::{PreparedData, model_rows, prepare, reference_statistics};
use crate::execute::feature_supply::feature_supply;
use crate::execute::fit::fit_and_score;
use crate::execute::results::{CameraFrames, ExperimentResults, ModelRows, RegressorResult};
use crate::execute::schemes::{SchemeInputs, run_schemes};
use crate::execute::traverses::{build_traverse, window_predictions};

/// A dataset, ready for every run that uses it.
pub struct Prepared {
    data: PreparedData,
    rows: ModelRows,
    /// Test traverses (only when a run with schemes uses the dataset),
    /// shared by every run's results.
    traverses: Arc<Vec<Traverse>>,
    /// The simulated testbed's ground as the camera sees it, built the
    /// first time a run's stereo VO asks for it.
    ground: GroundCell,
}

/// A trained regressor's scores and its window predictions on the
/// traverses (the model itself is not needed once they are made).
pub struct Fitted {
    result: RegressorResult,
    predictions: Option<Vec<Vec<ResidualPrediction>>>,
}

/// What was computed once.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SharedCounts {
    /// Distinct datasets prepared.
    pub datasets: usize,
    /// Distinct (dataset, regressor) fits.
    pub fits: usize,
}

/// A reference table's statistics (`compare_with`), by table.
type References = BTreeMap<String, Option<(String, ResidualStatistics)>>;

/// A distinct fit to make: the regressor, whether on |residual| targets,
/// its data and the folder its paths start from.
type FitJob<'a> = (&'a gpodo_regressors::RegressorSpec, bool, Arc<Prepared>);

/// A distinct fit, or why it failed: the regressor's label and the error.
type FitOutcome = Result<Arc<Fitted>, (String, String)>;

/// The shared work of a set of runs.
#[derive(Default)]
pub struct SharedWork {
    prepared: BTreeMap<String, Arc<Prepared>>,
    /// Each distinct fit, or why it failed (by label and error).
    fitted: BTreeMap<String, FitOutcome>,
    references: References,
    code_version: String,
    counts: SharedCounts,
}

fn json<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

/// The identity of a run's data: the dataset (its paths absolute), motion
/// model and residual settings.
pub fn dataset_key(config: &ExperimentConfig) -> String {
    format!(
        "{}|{}|{}",
        json(&config.dataset),
        json(&config.motion_model),
        json(&config.residuals)
    )
}

/// The identity of a run's reference table.
fn reference_key(config: &ExperimentConfig) -> String {
    json(&config.compare_with)
}

fn fit_key(dataset: &str, spec: &gpodo_regressors::RegressorSpec, absolute: bool) -> String {
    let targets = if absolute { "|residual|" } else { "residual" };
    format!("{dataset}|{targets}|{}", json(spec))
}

/// The rows with every target replaced by its absolute value: what a
/// |residual| regressor trains on and is scored against.
fn absolute_rows(rows: &gpodo_traits::ResidualDataset) -> gpodo_traits::ResidualDataset {
    let mut out = rows.clone();
    for i in 0..out.targets.nrows() {
        for v in out.targets.row_mut(i) {
            *v = v.abs();
        }
    }
    out
}

/// Whether a fit needing `needed` bytes runs alone: when `threads` of it
/// at once would need more than 80 % of the `available` memory (the rest
/// is room for what the estimate leaves out).
fn runs_alone(needed: Option<u64>, available: Option<u64>, threads: u64) -> bool {
    matches!(
        (needed, available),
        (Some(needed), Some(free)) if needed.saturating_mul(threads) > free / 5 * 4
    )
}

/// Fits one distinct regressor (on |residual| targets when `absolute`) and
/// predicts its windows on the traverses.
fn fit_shared(
    spec: &gpodo_regressors::RegressorSpec,
    absolute: bool,
    p: &Prepared,
    progress: Option<&MultiProgress>,
) -> Result<Arc<Fitted>, PipelineError> {
    let label = if absolute {
        crate::config::schemes::absolute_label(spec)
    } else {
        spec.label()
    };
    let spinner = progress.map(|m| FitSpinner::new(m, &label));
    // Without a spinner the fit still hears a stop (Ctrl-C).
    let sink: Option<Arc<dyn gpodo_traits::FitProgress>> = Some(match spinner.as_ref() {
        Some(s) => Arc::clone(s) as Arc<dyn gpodo_traits::FitProgress>,
        None => Arc::new(crate::util::stop::StopOnRequest),
    });
    let (mut result, model) = if absolute {
        let rows = ModelRows {
            train: absolute_rows(&p.rows.train),
            test: absolute_rows(&p.rows.test),
            test_windows: None,
        };
        fit_and_score(spec, &rows, sink)?
    } else {
        fit_and_score(spec, &p.rows, sink)?
    };
    result.label = label;
    if let Some(s) = spinner {
        s.bar.finish_and_clear();
    }
    let predictions = if p.traverses.is_empty() {
        None
    } else {
        Some(
            p.traverses
                .iter()
                .map(|t| window_predictions(model.as_ref(), t))
                .collect::<Result<Vec<_>, _>>()?,
        )
    };
    Ok(Arc::new(Fitted {
        result,
        predictions,
    }))
}

impl SharedWork {
    /// Prepares every distinct dataset and fits every distinct regressor of
    /// `runs`, in parallel within each stage.
    ///
    /// # Errors
    /// The first failure.
    pub fn build(
        runs: &[&ExperimentConfig],
        progress: Option<&MultiProgress>,
    ) -> Result<Self, PipelineError> {
        // Distinct datasets, and whether any run of each needs traverses.
        let mut datasets: BTreeMap<String, (&ExperimentConfig, bool)> = BTreeMap::new();
        for config in runs {
            let entry = datasets
                .entry(dataset_key(config))
                .or_insert((config, false));
            entry.1 |= !config.schemes.is_empty();
        }
        let prepared: Vec<(String, Arc<Prepared>)> = datasets
            .into_par_iter()
            .map(|(key, (config, needs_traverses))| {
                let start = Instant::now();
                let data = prepare(config)?;
                let (rows, scaler) = model_rows(&data)?;
                let traverses = if needs_traverses {
                    build_traverses(config, &data, &scaler)?
                } else {
                    Vec::new()
                };
                tracing::info!(secs = start.elapsed().as_secs_f64(), "dataset prepared");
                Ok((
                    key,
                    Arc::new(Prepared {
                        data,
                        rows,
                        traverses: Arc::new(traverses),
                        ground: std::sync::OnceLock::new(),
                    }),
                ))
            })
            .collect::<Result<_, PipelineError>>()?;
        let prepared: BTreeMap<String, Arc<Prepared>> = prepared.into_iter().collect();
        // Distinct fits: each regressor, and each |residual| regressor.
        let mut fits: BTreeMap<String, FitJob<'_>> = BTreeMap::new();
        for config in runs {
            let key = dataset_key(config);
            let Some(p) = prepared.get(&key) else {
                continue;
            };
            let specs = (config.regressors.iter().map(|s| (s, false)))
                .chain(config.absolute_regressors.iter().map(|s| (s, true)));
            for (spec, absolute) in specs {
                fits.entry(fit_key(&key, spec, absolute)).or_insert((
                    spec,
                    absolute,
                    Arc::clone(p),
                ));
            }
        }
        // A fit that fails fails only the runs that use it (an external
        // plugin's crash is the plugin's, not the sweep's).
        // Longest first, pulled one at a time (list scheduling): otherwise
        // a sweep on two cores can end with one long fit running alone.
        let mut fits: Vec<_> = fits
            .into_iter()
            .map(|(key, fit)| (fit.0.fit_cost(fit.2.rows.train.len()), key, fit))
            .collect();
        fits.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let run = |(key, (spec, absolute, p)): (String, FitJob<'_>)| {
            let fitted = fit_shared(spec, absolute, &p, progress).map_err(|e| {
                if crate::util::stop::requested() {
                    tracing::info!(regressor = %spec.label(), "fit stopped");
                } else {
                    tracing::warn!(regressor = %spec.label(), error = %e, "fit failed; the runs that use it are recorded as failed");
                }
                (spec.label(), e.to_string())
            });
            (key, fitted)
        };
        // Fits of which as many as there are threads would need more than
        // 80 % of the memory left (what the estimate leaves out needs room)
        // run one at a time: each checks the memory it needs before it
        // starts, a check two at once could both pass. The rest then run in
        // parallel.
        let available = crate::util::memory::available_bytes();
        let threads = rayon::current_num_threads() as u64;
        let (large, rest): (Vec<_>, Vec<_>) = fits
            .into_iter()
            .map(|(_, key, fit)| (key, fit))
            .partition(|(_, (spec, _, p))| {
                let rows = &p.rows.train;
                let (n, d, o) = (rows.len(), rows.inputs.ncols(), rows.targets.ncols());
                runs_alone(spec.fit_memory_bytes(n, d, o), available, threads)
            });
        let mut fitted: Vec<(String, FitOutcome)> = large.into_iter().map(run).collect();
        fitted.extend(rest.into_iter().par_bridge().map(run).collect::<Vec<_>>());
        let counts = SharedCounts {
            datasets: prepared.len(),
            fits: fitted.len(),
        };
        let mut references = References::new();
        for config in runs {
            references
                .entry(reference_key(config))
                .or_insert_with(|| reference_statistics(config));
        }
        Ok(Self {
            prepared,
            fitted: fitted.into_iter().collect(),
            references,
            code_version: code_version(),
            counts,
        })
    }

    /// `git describe` of the code that did the work.
    pub fn code_version(&self) -> &str {
        &self.code_version
    }

    /// What was computed once.
    pub fn counts(&self) -> SharedCounts {
        self.counts
    }

    /// A run's results from the shared work: its regressors' scores and its
    /// schemes (run here).
    ///
    /// # Errors
    /// [`PipelineError::Inconsistent`] for a run the work was not built
    /// for; what the schemes report.
    pub fn results(&self, config: &ExperimentConfig) -> Result<ExperimentResults, PipelineError> {
        let start = Instant::now();
        let key = dataset_key(config);
        let missing =
            || PipelineError::Inconsistent(format!("no shared work for `{}`", config.name));
        let p = self.prepared.get(&key).ok_or_else(missing)?;
        let fitted_of = |specs: &[gpodo_regressors::RegressorSpec], absolute: bool| {
            specs
                .iter()
                .map(
                    |spec| match self.fitted.get(&fit_key(&key, spec, absolute)) {
                        None => Err(missing()),
                        Some(Ok(f)) => Ok(f),
                        Some(Err((label, reason))) => Err(PipelineError::FitFailed {
                            label: label.clone(),
                            reason: reason.clone(),
                        }),
                    },
                )
                .collect::<Result<Vec<&Arc<Fitted>>, _>>()
        };
        let fitted = fitted_of(&config.regressors, false)?;
        let absolute = fitted_of(&config.absolute_regressors, true)?;
        let labels = config.regressor_labels();
        let absolute_labels = config.absolute_regressor_labels();
        let predictions: Vec<Option<Vec<Vec<ResidualPrediction>>>> =
            fitted.iter().map(|f| f.predictions.clone()).collect();
        let absolute_predictions: Vec<Option<Vec<Vec<ResidualPrediction>>>> =
            absolute.iter().map(|f| f.predictions.clone()).collect();
        let mut camera = CameraFrames::default();
        let schemes = if config.schemes.is_empty() {
            Vec::new()
        } else {
            tracing::info!(
                schemes = config.schemes.len(),
                runs = p.traverses.len(),
                "running Table II"
            );
            let traverses = with_feature_supply(config, p)?;
            let frames = camera_frames(config, &p.data, &p.ground, &traverses)?;
            let config = &with_derived_odometry(config, p);
            let schemes = run_schemes(&SchemeInputs {
                config,
                traverses: &traverses,
                predictions: &predictions,
                regressor_labels: &labels,
                absolute_predictions: &absolute_predictions,
                absolute_labels: &absolute_labels,
                recorded_vo: &p.data.recorded_vo,
                frames: &frames,
            })?;
            camera = CameraFrames(frames);
            schemes
        };
        let data = &p.data;
        Ok(ExperimentResults {
            config: config.clone(),
            code_version: self.code_version.clone(),
            train_statistics: residual_statistics(&data.train),
            test_statistics: residual_statistics(&data.test),
            reference_statistics: self
                .references
                .get(&reference_key(config))
                .cloned()
                .flatten(),
            dataset: data.summary.clone(),
            motion_model: data.motion_model.clone(),
            dead_reckoning: data.dead_reckoning.clone(),
            regressors: fitted.iter().map(|f| f.result.clone()).collect(),
            absolute_regressors: absolute.iter().map(|f| f.result.clone()).collect(),
            schemes,
            duration_secs: start.elapsed().as_secs_f64(),
            cpu_secs: None,
            train_rows: Some(data.train.clone()),
            test_rows: Some(data.test.clone()),
            traverses: Arc::clone(&p.traverses),
            window_predictions: predictions,
            camera_frames: camera,
        })
    }
}

/// A spinner line per running fit, showing the optimiser's iterations.
struct FitSpinner {
    bar: ProgressBar,
    label: String,
}

impl FitSpinner {
    fn new(multi: &MultiProgress, label: &str) -> Arc<Self> {
        let bar = multi.add(ProgressBar::new_spinner());
        if let Ok(style) = ProgressStyle::with_template("  {spinner} {msg} ({elapsed})") {
            bar.set_style(style);
        }
        bar.set_message(format!("{label}: fitting"));
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        Arc::new(Self {
            bar,
            label: label.to_string(),
        })
    }
}

impl gpodo_traits::FitProgress for FitSpinner {
    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> std::ops::ControlFlow<()> {
        self.bar.set_message(format!(
            "{}: start {start}, iteration {iteration}, objective {objective:.2}",
            self.label
        ));
        crate::util::stop::control_flow()
    }
}

/// The test traverses as the run's simulated tracker sees them: with the
/// feature supply of its camera over the testbed's soils (a borrowed copy
/// of the shared ones when there is no soil map or the tracker ignores it).
fn with_feature_supply<'a>(
    config: &ExperimentConfig,
    p: &'a Prepared,
) -> Result<std::borrow::Cow<'a, [Traverse]>, PipelineError> {
    use gpodo_frontends::params::VoSpec;
    let (Some(soils), VoSpec::Simulated(vo)) = (&p.data.soils, &config.frontend.vo) else {
        return Ok(std::borrow::Cow::Borrowed(p.traverses.as_slice()));
    };
    if !vo.terrain_features {
        return Ok(std::borrow::Cow::Borrowed(p.traverses.as_slice()));
    }
    let traverses = p
        .traverses
        .iter()
        .map(|t| {
            let supply = feature_supply(soils, &vo.camera, vo.texture_contrast, t);
            t.clone().with_feature_supply(supply)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(std::borrow::Cow::Owned(traverses))
}

/// The run's configuration with what the dataset tells of its odometry:
/// the gyro bias of a simulated testbed when the experiment leaves
/// `frontend.odometry.rotation_bias_radps` unset.
fn with_derived_odometry<'a>(
    config: &'a ExperimentConfig,
    p: &Prepared,
) -> std::borrow::Cow<'a, ExperimentConfig> {
    match (
        config.frontend.odometry.rotation_bias_radps,
        p.data.gyro_bias_radps,
    ) {
        (None, Some(bias)) => {
            let mut resolved = config.clone();
            resolved.frontend.odometry.rotation_bias_radps = Some(bias);
            std::borrow::Cow::Owned(resolved)
        }
        _ => std::borrow::Cow::Borrowed(config),
    }
}

/// The test traverses of a dataset.
fn build_traverses(
    config: &ExperimentConfig,
    data: &PreparedData,
    scaler: &Standardizer,
) -> Result<Vec<Traverse>, PipelineError> {
    let Some((model, radius)) = &data.model else {
        return Ok(Vec::new());
    };
    let window = config.residuals.window_secs.unwrap_or(1.0);
    data.test_logs
        .iter()
        .map(|log| build_traverse(log, model.as_ref(), *radius, window, scaler))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::runs_alone;

    #[test]
    fn fits_that_two_at_once_would_not_leave_a_fifth_of_the_memory_run_alone() {
        const GB: u64 = 1_000_000_000;
        // The full-rate exact GP (10.05 GB estimated) on 24.5 GB, 2 threads.
        assert!(runs_alone(Some(10 * GB), Some(24 * GB), 2));
        assert!(!runs_alone(Some(10 * GB), Some(24 * GB), 1));
        assert!(!runs_alone(Some(GB), Some(24 * GB), 2));
        // Unknown needs or memory: in parallel.
        assert!(!runs_alone(None, Some(GB), 2));
        assert!(!runs_alone(Some(u64::MAX), None, 2));
    }
}
