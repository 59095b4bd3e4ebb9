//! The prequential protocol of `gpodo bench` (`bench: {prequential:
//! {blocks: K}}`): the training stream is cut, in time order, into `K`
//! blocks. For each block `k ≥ 2` the baseline (the exact GP) is fitted on
//! blocks `1…k−1` and predicts block `k`: the best a batch learner could do
//! with what the robot has seen. An exact GP's refit is fitted from the
//! start policy (cold), from the previous refit's optimum alone (warm), or
//! both with the higher log marginal likelihood kept (`refit_start`). Each
//! online learner predicts every sample of blocks `2…K` before learning it
//! (test-then-train), from an empty model. Beside them, two baselines that need no model: predicting no
//! residual (with the past targets' mean square as its variance) and the
//! running mean of the past targets (with their variance). Scores are
//! pooled over every output of every scored sample: RMSE, and the mean
//! Gaussian NLPD `½ ln 2πσ² + (y − μ)²/2σ²`.

use std::time::Instant;

use gpodo_regressors::RegressorSpec;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpState};
use gpodo_traits::{FitReport, ResidualDataset, ResidualRegressor};
use serde::{Deserialize, Serialize};

use crate::config::{PrequentialSettings, RefitStart};
use crate::error::PipelineError;
use crate::execute::latency::Latency;

/// One contender's prequential scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PrequentialScore {
    /// Its label.
    pub label: String,
    /// RMSE pooled over the scored samples and outputs.
    pub rmse: f64,
    /// Mean NLPD over the same.
    pub nlpd: f64,
    /// An online learner's update latency.
    pub update_latency: Option<Latency>,
    /// The RMSE pooled over blocks 2…k, for k = 2…K (the figure's curve).
    #[serde(default)]
    pub cumulative_rmse: Vec<f64>,
}

/// What the prequential protocol measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prequential {
    /// Blocks `K`.
    pub blocks: usize,
    /// Training rows in a block (the last may hold fewer).
    pub block_rows: usize,
    /// Samples scored (blocks 2…K).
    pub scored: usize,
    /// The baseline refitted on each prefix (the yardstick).
    pub refitted: PrequentialScore,
    /// Each refit, block 2 first.
    pub refits: Vec<Refit>,
    /// Predicting no residual, and the running mean.
    pub baselines: Vec<PrequentialScore>,
    /// Each online learner of the experiment.
    pub learners: Vec<PrequentialScore>,
}

/// One fit of the baseline on a prefix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitRecord {
    /// Its log marginal likelihood (standardised units), when it has one.
    pub lml: Option<f64>,
    /// Objective evaluations, when it learned hyperparameters.
    pub evaluations: Option<usize>,
    /// Seconds of the fit.
    pub seconds: f64,
}

/// One refit of the baseline on a prefix: its cold and its warm fit, as
/// many as were run, and which one predicted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Refit {
    /// Rows of the prefix.
    pub rows: usize,
    /// The fit from the start policy.
    pub cold: Option<FitRecord>,
    /// The fit from the previous refit's optimum alone.
    pub warm: Option<FitRecord>,
    /// Whether the warm fit was kept.
    pub kept_warm: bool,
}

impl Refit {
    /// Seconds of every fit on this prefix.
    pub fn seconds(&self) -> f64 {
        self.cold.iter().chain(&self.warm).map(|f| f.seconds).sum()
    }
}

/// The baseline fitted on a prefix, ready to predict.
struct Fitted {
    model: Box<dyn ResidualRegressor>,
    report: FitReport,
    /// An exact GP's state, the next refit's warm start.
    state: Option<ExactGpState>,
}

impl Fitted {
    fn record(&self, seconds: f64) -> FitRecord {
        FitRecord {
            lml: self.report.objective,
            evaluations: self.report.evaluations,
            seconds,
        }
    }
}

/// Fits `baseline` on `data`, timed; an exact GP starts from `warm`'s
/// optimum alone when it is given.
fn fit_baseline(
    baseline: &RegressorSpec,
    data: &ResidualDataset,
    warm: Option<&ExactGpState>,
) -> Result<(Fitted, FitRecord), PipelineError> {
    crate::execute::fit::check_memory(
        baseline,
        &baseline.label(),
        data,
        crate::util::memory::available_bytes(),
    )?;
    let t = Instant::now();
    let fitted = fit_untimed(baseline, data, warm)?;
    let record = fitted.record(t.elapsed().as_secs_f64());
    Ok((fitted, record))
}

fn fit_untimed(
    baseline: &RegressorSpec,
    data: &ResidualDataset,
    warm: Option<&ExactGpState>,
) -> Result<Fitted, PipelineError> {
    let wrap = |source| PipelineError::Regressor {
        label: baseline.label(),
        source,
    };
    if let RegressorSpec::ExactGp(params) = baseline {
        let mut gp = ExactGp::new(params.clone()).map_err(|e| wrap(e.into()))?;
        if let Some(previous) = warm {
            gp.warm_start_from(previous).map_err(|e| wrap(e.into()))?;
        }
        let report = gp.fit(data).map_err(wrap)?;
        let state = gp.state().cloned();
        return Ok(Fitted {
            model: Box::new(gp),
            report,
            state,
        });
    }
    let mut model = baseline.build()?;
    let report = model.fit(data).map_err(wrap)?;
    Ok(Fitted {
        model,
        report,
        state: None,
    })
}

/// The refits (block 2 is refit 0, always cold) that are also fitted cold
/// under `refit_start: warm`: `count` of the warm ones, evenly spaced, the
/// last included.
fn cold_check_refits(refits: usize, count: usize) -> Vec<usize> {
    let warm = refits.saturating_sub(1);
    let count = count.min(warm);
    let mut picked: Vec<usize> = (1..=count).map(|c| (warm * c).div_ceil(count)).collect();
    picked.dedup();
    picked
}

/// Pooled squared error and NLPD, and the RMSE pooled up to each block.
#[derive(Debug, Default, Clone)]
struct Tally {
    squared: f64,
    nlpd: f64,
    count: usize,
    /// `(block, cumulative RMSE)` at the end of each block seen.
    cumulative: Vec<(usize, f64)>,
}

impl Tally {
    /// One scored value of block `block`.
    fn add(&mut self, block: usize, mean: f64, variance: f64, y: f64) {
        let var = variance.max(1e-300);
        self.squared += (y - mean).powi(2);
        self.nlpd += 0.5 * (std::f64::consts::TAU * var).ln() + (y - mean).powi(2) / (2.0 * var);
        self.count += 1;
        let rmse = (self.squared / self.count as f64).sqrt();
        match self.cumulative.last_mut() {
            Some((b, r)) if *b == block => *r = rmse,
            _ => self.cumulative.push((block, rmse)),
        }
    }

    fn score(&self, label: String, update_latency: Option<Latency>) -> PrequentialScore {
        let n = self.count.max(1) as f64;
        PrequentialScore {
            label,
            rmse: (self.squared / n).sqrt(),
            nlpd: self.nlpd / n,
            update_latency,
            cumulative_rmse: self.cumulative.iter().map(|c| c.1).collect(),
        }
    }
}

/// Rows `range` of `data`.
fn rows(
    data: &ResidualDataset,
    range: std::ops::Range<usize>,
) -> Result<ResidualDataset, PipelineError> {
    let index: Vec<usize> = range.collect();
    Ok(ResidualDataset::new(
        data.inputs.select_rows(&index),
        data.targets.select_rows(&index),
        data.input_names.clone(),
        data.target_names.clone(),
    )?
    .with_standardized_inputs(data.inputs_standardized))
}

/// Runs the protocol on `train` (time order) with `settings.blocks`
/// blocks, the `baseline` spec as the refitted yardstick and every online
/// learner of `specs`.
///
/// # Errors
/// [`PipelineError`] naming the regressor that failed.
pub fn prequential(
    train: &ResidualDataset,
    settings: &PrequentialSettings,
    baseline: &RegressorSpec,
    specs: &[RegressorSpec],
) -> Result<Prequential, PipelineError> {
    let blocks = settings.blocks;
    let n = train.len();
    let block_rows = n.div_ceil(blocks.max(1)).max(1);
    let first = block_rows.min(n);
    let p = train.targets.ncols();
    let wrap = |label: String| move |source| PipelineError::Regressor { label, source };

    // The yardstick: refitted on each prefix, predicting the next block.
    let mut refitted = Tally::default();
    let mut refits = Vec::new();
    let refit_count = n.saturating_sub(first).div_ceil(block_rows);
    let checked = cold_check_refits(refit_count, settings.cold_checks);
    let mut previous: Option<ExactGpState> = None;
    let mut start = first;
    while start < n {
        let end = (start + block_rows).min(n);
        let prefix = rows(train, 0..start)?;
        let (warm_from, run_cold) = match (settings.refit_start, previous.as_ref()) {
            (_, None) | (RefitStart::Cold, _) => (None, true),
            (RefitStart::Warm, Some(p)) => (Some(p), checked.contains(&refits.len())),
            (RefitStart::Best, Some(p)) => (Some(p), true),
        };
        let warm = warm_from
            .map(|p| fit_baseline(baseline, &prefix, Some(p)))
            .transpose()?;
        let cold = if run_cold {
            Some(fit_baseline(baseline, &prefix, None)?)
        } else {
            None
        };
        let lml = |f: &Option<(Fitted, FitRecord)>| {
            f.as_ref()
                .and_then(|f| f.1.lml)
                .unwrap_or(f64::NEG_INFINITY)
        };
        let kept_warm = warm.is_some()
            && (settings.refit_start != RefitStart::Best || lml(&warm) >= lml(&cold));
        refits.push(Refit {
            rows: start,
            cold: cold.as_ref().map(|f| f.1.clone()),
            warm: warm.as_ref().map(|f| f.1.clone()),
            kept_warm,
        });
        let Some((fitted, _)) = (if kept_warm { warm } else { cold }) else {
            return Err(PipelineError::Inconsistent(
                "a prequential refit ran no fit".into(),
            ));
        };
        previous = fitted.state;
        let model = fitted.model;
        let block = rows(train, start..end)?;
        let predicted = model
            .predict(&block.inputs)
            .map_err(wrap(baseline.label()))?;
        let k = start / block_rows;
        for i in 0..block.len() {
            for j in 0..p {
                refitted.add(
                    k,
                    predicted.mean.get(i, j),
                    predicted.variance.get(i, j),
                    block.targets.get(i, j),
                );
            }
        }
        tracing::info!(rows = start, "prequential refit");
        start = end;
    }

    // The baselines, from the past targets' running moments.
    let (mut zero, mut mean) = (Tally::default(), Tally::default());
    let (mut sum, mut sum_sq) = (vec![0.0; p], vec![0.0; p]);
    for i in 0..n {
        let y = train.targets.row(i);
        if i >= first {
            let k = i as f64;
            for j in 0..p {
                let m = sum[j] / k;
                let mean_square = sum_sq[j] / k;
                let variance = if i > 1 {
                    (sum_sq[j] - k * m * m) / (k - 1.0)
                } else {
                    mean_square
                };
                zero.add(i / block_rows, 0.0, mean_square, y[j]);
                mean.add(i / block_rows, m, variance, y[j]);
            }
        }
        for j in 0..p {
            sum[j] += y[j];
            sum_sq[j] += y[j] * y[j];
        }
    }

    // Each online learner: test, then train, from an empty model.
    let mut learners = Vec::new();
    for spec in specs {
        let mut model: Box<dyn ResidualRegressor> = spec.build()?;
        if !model.supports_online_update() {
            continue;
        }
        let mut tally = Tally::default();
        let mut updates = Vec::with_capacity(n);
        for i in 0..n {
            if i >= first {
                let predicted = model
                    .predict(&train.inputs.select_rows(&[i]))
                    .map_err(wrap(spec.label()))?;
                for j in 0..p {
                    tally.add(
                        i / block_rows,
                        predicted.mean.get(0, j),
                        predicted.variance.get(0, j),
                        train.targets.get(i, j),
                    );
                }
            }
            let t = Instant::now();
            model
                .update(train.inputs.row(i), train.targets.row(i))
                .map_err(wrap(spec.label()))?;
            updates.push(t.elapsed().as_secs_f64() * 1e6);
        }
        learners.push(tally.score(spec.label(), Some(Latency::of(updates))));
    }

    Ok(Prequential {
        blocks,
        block_rows,
        scored: n.saturating_sub(first),
        refitted: refitted.score(format!("{} refitted on the prefix", baseline.label()), None),
        refits,
        baselines: vec![
            zero.score("predicting no residual".into(), None),
            mean.score("running mean".into(), None),
        ],
        learners,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gpodo_traits::SampleMatrix;

    #[test]
    fn the_baselines_score_the_past_targets_moments_by_hand() {
        // One output, four rows, two blocks of two: rows 2 and 3 are scored.
        let y = [1.0, 3.0, 2.0, 6.0];
        let data = ResidualDataset::new(
            SampleMatrix::from_row_major(4, 1, vec![0.0, 1.0, 2.0, 3.0]).unwrap(),
            SampleMatrix::from_row_major(4, 1, y.to_vec()).unwrap(),
            vec!["x".into()],
            vec!["y".into()],
        )
        .unwrap();
        let spec = RegressorSpec::Zero {
            variance: Some(1.0),
        };
        let settings = PrequentialSettings {
            blocks: 2,
            ..PrequentialSettings::default()
        };
        let r = prequential(&data, &settings, &spec, &[]).unwrap();
        assert_eq!((r.block_rows, r.scored), (2, 2));
        // Running mean: 2 (from 1, 3), then 2 (from 1, 3, 2).
        let rmse = ((0.0f64.powi(2) + 4.0f64.powi(2)) / 2.0).sqrt();
        assert!((r.baselines[1].rmse - rmse).abs() < 1e-12);
        // No residual: errors 2 and 6.
        assert!((r.baselines[0].rmse - ((4.0 + 36.0) / 2.0f64).sqrt()).abs() < 1e-12);
        // Its NLPD uses the mean squares 5 and 14/3.
        let nlpd = |v: f64, e: f64| 0.5 * (std::f64::consts::TAU * v).ln() + e * e / (2.0 * v);
        let expected = (nlpd(5.0, 2.0) + nlpd(14.0 / 3.0, 6.0)) / 2.0;
        assert!((r.baselines[0].nlpd - expected).abs() < 1e-12);
        // The zero model refitted on the prefix predicts 0 with variance 1.
        let expected = (nlpd(1.0, 2.0) + nlpd(1.0, 6.0)) / 2.0;
        assert!((r.refitted.nlpd - expected).abs() < 1e-12);
        assert_eq!(r.refits.len(), 1);
        assert!(r.refits[0].warm.is_none() && r.refits[0].cold.is_some());
        // One scored block: its cumulative RMSE is the pooled one.
        assert_eq!(r.baselines[1].cumulative_rmse, vec![r.baselines[1].rmse]);
    }

    #[test]
    fn refits_start_cold_warm_or_both_and_best_keeps_the_higher_likelihood() {
        use gpodo_regressors::exact_gp::ExactGpParams;
        // A smooth function of two inputs, 80 rows in 4 blocks: 3 refits.
        let n = 80;
        let x: Vec<f64> = (0..2 * n)
            .map(|i| ((i * 37) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|i| (2.0 * x[2 * i]).sin() + 0.5 * x[2 * i + 1] + 0.01 * ((i % 7) as f64 - 3.0))
            .collect();
        let data = ResidualDataset::new(
            SampleMatrix::from_row_major(n, 2, x).unwrap(),
            SampleMatrix::from_row_major(n, 1, y).unwrap(),
            vec!["a".into(), "b".into()],
            vec!["y".into()],
        )
        .unwrap();
        let spec = RegressorSpec::ExactGp(ExactGpParams::default());
        let run = |refit_start, cold_checks| {
            let settings = PrequentialSettings {
                blocks: 4,
                refit_start,
                cold_checks,
            };
            prequential(&data, &settings, &spec, &[]).unwrap()
        };
        let best = run(RefitStart::Best, 0);
        assert_eq!(best.refits.len(), 3);
        assert!(best.refits[0].warm.is_none());
        for r in &best.refits[1..] {
            let (c, w) = (r.cold.as_ref().unwrap(), r.warm.as_ref().unwrap());
            let (c, w) = (c.lml.unwrap(), w.lml.unwrap());
            assert_eq!(r.kept_warm, w >= c, "{r:?}");
        }
        let warm = run(RefitStart::Warm, 1);
        assert!(warm.refits[1].cold.is_none() && warm.refits[1].warm.is_some());
        assert!(warm.refits[2].cold.is_some() && warm.refits[2].kept_warm);
        let cold = run(RefitStart::Cold, 2);
        assert!(cold.refits.iter().all(|r| r.warm.is_none() && !r.kept_warm));
        // Each start's fits are the same fits whichever mode runs them.
        for (a, b) in best.refits.iter().zip(&cold.refits) {
            assert_eq!(a.cold.as_ref().unwrap().lml, b.cold.as_ref().unwrap().lml);
        }
        assert_eq!(
            best.refits[1].warm.as_ref().unwrap().lml,
            warm.refits[1].warm.as_ref().unwrap().lml
        );
    }

    #[test]
    fn cold_checks_fall_on_warm_refits_evenly_the_last_included() {
        // Under `refit_start: warm`.
        // Nine refits (blocks 2…10): refit 0 is cold, 1…8 warm.
        assert_eq!(cold_check_refits(9, 2), vec![4, 8]);
        assert_eq!(cold_check_refits(9, 1), vec![8]);
        assert_eq!(cold_check_refits(9, 0), Vec::<usize>::new());
        assert_eq!(cold_check_refits(3, 5), vec![1, 2]);
        assert_eq!(cold_check_refits(1, 2), Vec::<usize>::new());
    }
}
