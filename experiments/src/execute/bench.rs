//! `gpodo bench`: every regressor of an experiment file on the same data
//! and splits, timed one after another (never in parallel, so timings do
//! not disturb each other): fit time, per-query prediction latency,
//! per-sample online update latency (for online learners), RMSE, MAE,
//! NLPD, 95 % coverage, and for online learners the learning curve (test
//! error after every N samples of one prequential pass). Ratios to the
//! exact-GP baseline are taken in the report.

use std::time::Instant;

use gpodo_regressors::RegressorSpec;
use gpodo_regressors::metrics::{Evaluation, evaluate};
use gpodo_traits::{FitReport, ResidualDataset, ResidualRegressor, SampleMatrix};
use serde::{Deserialize, Serialize};

use crate::config::ExperimentConfig;
use crate::error::PipelineError;
use crate::execute::code_version;
use crate::execute::data::prepare_model_rows;
use crate::execute::latency::Latency;
use crate::execute::results::{DatasetSummary, ModelRows};

/// One point of a learning curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Training samples seen.
    pub samples: usize,
    /// Pooled RMSE on the test rows.
    pub rmse: f64,
    /// Pooled MAE on the test rows.
    pub mae: f64,
    /// Mean NLPD on the test rows.
    pub nlpd: f64,
}

/// One prequential online pass: each training sample is first predicted,
/// then learned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnlinePass {
    /// Latency of one single-row prediction plus one update, per sample.
    pub step_latency: Latency,
    /// Latency of the update alone.
    pub update_latency: Latency,
    /// Test scores after every `learning_curve_every` samples, and at the end.
    pub curve: Vec<CurvePoint>,
    /// Test scores after the pass.
    pub evaluation: Evaluation,
}

/// One regressor's benchmark.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchRow {
    /// Label for tables.
    pub label: String,
    /// Its specification.
    pub spec: RegressorSpec,
    /// What the batch fit did (its duration is the fit time).
    pub fit: FitReport,
    /// Latency of a one-row prediction after the fit.
    pub predict_latency: Latency,
    /// Time to predict all test rows at once (s).
    pub batch_predict_secs: f64,
    /// Test scores after the batch fit.
    pub evaluation: Evaluation,
    /// The online pass, for learners that support it.
    pub online: Option<OnlinePass>,
}

/// Everything `gpodo bench` measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchResults {
    /// The configuration.
    pub config: ExperimentConfig,
    /// `git describe` of the code.
    pub code_version: String,
    /// The data.
    pub dataset: DatasetSummary,
    /// Index of the baseline row, if there is one.
    pub baseline: Option<usize>,
    /// One row per regressor that ran, in config order.
    pub rows: Vec<BenchRow>,
    /// The regressors that failed (label and reason); the others ran.
    #[serde(default)]
    pub failures: Vec<(String, String)>,
    /// The prequential protocol, when `bench.prequential` asks for it.
    #[serde(default)]
    pub prequential: Option<crate::execute::prequential::Prequential>,
    /// Wall-clock duration (s).
    pub duration_secs: f64,
}

/// Row `i` (in range) as a one-row matrix.
fn single_row(m: &SampleMatrix, i: usize) -> SampleMatrix {
    m.select_rows(&[i])
}

fn micros(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e6
}

fn predict_latency(
    model: &dyn ResidualRegressor,
    test: &ResidualDataset,
    queries: usize,
) -> Result<Latency, PipelineError> {
    let n = test.len().min(queries);
    let mut samples = Vec::with_capacity(n);
    for i in 0..n {
        let row = single_row(&test.inputs, i);
        let t = Instant::now();
        let p = model.predict(&row)?;
        samples.push(micros(t));
        std::hint::black_box(p);
    }
    Ok(Latency::of(samples))
}

fn curve_point(
    model: &dyn ResidualRegressor,
    test: &ResidualDataset,
    samples: usize,
) -> Result<CurvePoint, PipelineError> {
    let e = evaluate(&model.predict(&test.inputs)?, &test.targets)?;
    Ok(CurvePoint {
        samples,
        rmse: e.pooled.rmse,
        mae: e.pooled.mae,
        nlpd: e.pooled.nlpd,
    })
}

/// One prequential pass of a fresh learner over the training rows in order.
fn online_pass(
    spec: &RegressorSpec,
    rows: &ModelRows,
    every: usize,
) -> Result<OnlinePass, PipelineError> {
    let mut model = spec.build()?;
    let (mut steps, mut updates, mut curve) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..rows.train.len() {
        let x = rows.train.inputs.row(i);
        let y = rows.train.targets.row(i);
        let query = single_row(&rows.train.inputs, i);
        let t = Instant::now();
        // Before the first sample there is nothing to predict with.
        let prediction = if i > 0 {
            Some(model.predict(&query)?)
        } else {
            None
        };
        let u = Instant::now();
        model.update(x, y)?;
        updates.push(micros(u));
        steps.push(micros(t));
        std::hint::black_box(prediction);
        if (i + 1).is_multiple_of(every) {
            curve.push(curve_point(model.as_ref(), &rows.test, i + 1)?);
        }
    }
    if !rows.train.len().is_multiple_of(every) {
        curve.push(curve_point(model.as_ref(), &rows.test, rows.train.len())?);
    }
    let evaluation = evaluate(&model.predict(&rows.test.inputs)?, &rows.test.targets)?;
    Ok(OnlinePass {
        step_latency: Latency::of(steps),
        update_latency: Latency::of(updates),
        curve,
        evaluation,
    })
}

/// The baseline row: `settings.baseline`, else the first exact GP.
pub fn baseline_index(config: &ExperimentConfig) -> Option<usize> {
    config.bench.baseline.or_else(|| {
        config
            .regressors
            .iter()
            .position(|r| matches!(r, RegressorSpec::ExactGp(_)))
    })
}

/// Benchmarks every regressor of `config`; relative paths are resolved
/// against `base`.
///
/// # Errors
/// [`PipelineError`] naming the stage or regressor that failed.
pub fn run_bench(config: &ExperimentConfig) -> Result<BenchResults, PipelineError> {
    let start = Instant::now();
    let (rows, dataset) = prepare_model_rows(config)?;
    let settings = &config.bench;
    let mut out = Vec::with_capacity(config.regressors.len());
    let mut failures = Vec::new();
    // A regressor that fails (e.g. a plugin that crashes) is reported as
    // failed; the others are benchmarked.
    for spec in &config.regressors {
        match bench_one(spec, &rows, settings) {
            Ok(row) => out.push(row),
            Err(e) => {
                tracing::warn!(regressor = %spec.label(), error = %e, "benchmark failed");
                failures.push((spec.label(), e.to_string()));
            }
        }
    }
    let baseline = baseline_index(config).and_then(|i| {
        let label = config.regressors[i].label();
        out.iter().position(|r| r.label == label)
    });
    let prequential = match settings.prequential {
        Some(p) => {
            let Some(i) = baseline_index(config) else {
                return Err(PipelineError::Inconsistent(
                    "`bench.prequential` refits a baseline: add an exact_gp (or set `bench.baseline`)"
                        .into(),
                ));
            };
            Some(crate::execute::prequential::prequential(
                &rows.train,
                &p,
                &config.regressors[i],
                &config.regressors,
            )?)
        }
        None => None,
    };
    Ok(BenchResults {
        config: config.clone(),
        code_version: code_version(),
        dataset,
        baseline,
        rows: out,
        failures,
        prequential,
        duration_secs: start.elapsed().as_secs_f64(),
    })
}

/// Benchmarks one regressor.
fn bench_one(
    spec: &RegressorSpec,
    rows: &ModelRows,
    settings: &crate::config::bench::BenchSettings,
) -> Result<BenchRow, PipelineError> {
    let label = spec.label();
    let wrap = |source| PipelineError::Regressor {
        label: label.clone(),
        source,
    };
    crate::execute::fit::check_memory(
        spec,
        &label,
        &rows.train,
        crate::util::memory::available_bytes(),
    )?;
    tracing::info!(regressor = %label, n = rows.train.len(), "benchmarking");
    let mut model = spec.build()?;
    let fit = model.fit(&rows.train).map_err(wrap)?;
    let t = Instant::now();
    let predictions = model.predict(&rows.test.inputs).map_err(wrap)?;
    let batch_predict_secs = t.elapsed().as_secs_f64();
    let evaluation = rows.score(&predictions)?;
    let predict_latency = predict_latency(model.as_ref(), &rows.test, settings.predict_queries)?;
    let online = if model.supports_online_update() {
        Some(online_pass(spec, rows, settings.learning_curve_every)?)
    } else {
        None
    };
    Ok(BenchRow {
        label,
        spec: spec.clone(),
        fit,
        predict_latency,
        batch_predict_secs,
        evaluation,
        online,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_statistics_match_a_hand_computation() {
        let l = Latency::of(vec![5.0, 1.0, 3.0, 2.0, 4.0]);
        assert_eq!(l.count, 5);
        assert_eq!(l.median_us, 3.0);
        assert_eq!(l.p95_us, 5.0);
        assert_eq!(l.mean_us, 3.0);
    }
}
