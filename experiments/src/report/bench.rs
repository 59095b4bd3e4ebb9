//! Writes `bench.md` (tables with ratios to the baseline row) and
//! `bench.json` (everything measured), atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::execute::bench::{BenchResults, BenchRow};
use crate::execute::latency::Latency;
use crate::execute::prequential::FitRecord;
use crate::report::table::{Align, Table};
use crate::util::output::write_file;

/// Writes `bench.md` and `bench.json` into `dir` and returns their paths.
///
/// # Errors
/// Any I/O or serialisation error.
pub fn write_bench_report(r: &BenchResults, dir: &Path) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(dir)?;
    let md = dir.join("bench.md");
    let json = dir.join("bench.json");
    write_file(&json, serde_json::to_string_pretty(r)?.as_bytes())?;
    if let Some(p) = &r.prequential {
        let plots = dir.join("plots");
        std::fs::create_dir_all(&plots)?;
        let svg = crate::report::prequential_plot::prequential_svg(p)?;
        write_file(&plots.join("prequential.svg"), svg.as_bytes())?;
    }
    write_file(&md, bench_markdown(r).as_bytes())?;
    Ok((md, json))
}

fn ratio(value: f64, baseline: Option<f64>) -> String {
    match baseline {
        Some(b) if b > 0.0 && value.is_finite() => format!("{:.3}", value / b),
        _ => "–".into(),
    }
}

fn speedup(value: f64, baseline: Option<f64>) -> String {
    match baseline {
        Some(b) if value > 0.0 && b.is_finite() => format!("{:.1}×", b / value),
        _ => "–".into(),
    }
}

/// The Markdown report.
pub fn bench_markdown(r: &BenchResults) -> String {
    let mut s = String::new();
    let c = &r.config;
    let _ = writeln!(s, "# Regressor benchmark `{}`\n", c.name);
    if let Some(d) = &c.description {
        let _ = writeln!(s, "{}\n", d.trim());
    }
    let base: Option<&BenchRow> = r.baseline.and_then(|i| r.rows.get(i));
    let _ = writeln!(
        s,
        "Data: {}. Training rows: {}, test rows: {}, {} inputs. Code: `{}`. Wall time: {:.1} s. Regressors run one after another on one machine; times are wall clock. Baseline: {}.\n",
        r.dataset.source,
        r.dataset.n_train,
        r.dataset.n_test,
        r.dataset.input_names.len(),
        r.code_version,
        r.duration_secs,
        base.map_or("none (no exact GP in this file)".into(), |b| format!(
            "`{}`",
            b.label
        )),
    );
    let b_fit = base.map(|b| b.fit.duration_secs);
    let b_pred = base.map(|b| b.predict_latency.median_us);
    let b_rmse = base.map(|b| b.evaluation.pooled.rmse);
    let mut batch = Table::new(&[
        "Regressor",
        "fit [s]",
        "fit speed-up",
        "predict [µs/query] (median)",
        "predict speed-up",
        "batch predict [s]",
        "RMSE",
        "RMSE ratio",
        "MAE",
        "NLPD",
        "95% coverage",
    ]);
    for row in &r.rows {
        let e = &row.evaluation.pooled;
        batch.push(vec![
            row.label.clone(),
            format!("{:.3}", row.fit.duration_secs),
            speedup(row.fit.duration_secs, b_fit),
            format!("{:.1}", row.predict_latency.median_us),
            speedup(row.predict_latency.median_us, b_pred),
            format!("{:.4}", row.batch_predict_secs),
            format!("{:.6}", e.rmse),
            ratio(e.rmse, b_rmse),
            format!("{:.6}", e.mae),
            format!("{:.3}", e.nlpd),
            format!("{:.3}", e.coverage95),
        ]);
    }
    let _ = writeln!(
        s,
        "## Batch fit and prediction\n\nFit on all training rows; scores on the test rows (pooled over the outputs). Speed-up = baseline time / this time; RMSE ratio = this / baseline.\n\n{}",
        batch.markdown()
    );
    if !r.failures.is_empty() {
        let _ = writeln!(s, "**Failed** (not in the tables):\n");
        for (label, reason) in &r.failures {
            let _ = writeln!(
                s,
                "- {label}: {}",
                reason.lines().next().unwrap_or_default()
            );
        }
        s.push('\n');
    }
    let online: Vec<&BenchRow> = r.rows.iter().filter(|row| row.online.is_some()).collect();
    if online.is_empty() {
        return s;
    }
    let mut passes = Table::new(&[
        "Regressor",
        "predict + update median",
        "p95",
        "update median",
        "RMSE after one pass",
        "RMSE ratio",
        "MAE",
        "NLPD",
        "95% coverage",
    ]);
    for row in &online {
        let Some(o) = &row.online else { continue };
        let e = &o.evaluation.pooled;
        passes.push(vec![
            row.label.clone(),
            format!("{:.1}", o.step_latency.median_us),
            format!("{:.1}", o.step_latency.p95_us),
            format!("{:.1}", o.update_latency.median_us),
            format!("{:.6}", e.rmse),
            ratio(e.rmse, b_rmse),
            format!("{:.6}", e.mae),
            format!("{:.3}", e.nlpd),
            format!("{:.3}", e.coverage95),
        ]);
    }
    let _ = write!(
        s,
        "## Online learning\n\nOne prequential pass over the training rows in time order, from an empty model: each sample is predicted, then learned. Latencies per sample (µs); scores on the test rows after the pass.\n\n{}",
        passes.markdown()
    );
    let _ = writeln!(
        s,
        "\n### Learning curve\n\nPooled test RMSE after every {} training samples{}.\n",
        c.bench.learning_curve_every,
        b_rmse.map_or(String::new(), |b| format!(" (baseline batch RMSE {b:.6})"))
    );
    let mut curve = Table::new(
        &std::iter::once("samples".to_string())
            .chain(online.iter().map(|row| row.label.clone()))
            .collect::<Vec<_>>(),
    )
    .align(&[0], Align::Right);
    let points = online
        .iter()
        .filter_map(|row| row.online.as_ref().map(|o| o.curve.len()))
        .max()
        .unwrap_or(0);
    for k in 0..points {
        let samples = online
            .iter()
            .filter_map(|row| row.online.as_ref()?.curve.get(k).map(|p| p.samples))
            .next()
            .unwrap_or(0);
        let cells = online.iter().map(|row| {
            row.online
                .as_ref()
                .and_then(|o| o.curve.get(k))
                .map_or("–".into(), |p| format!("{:.6}", p.rmse))
        });
        curve.push(std::iter::once(samples.to_string()).chain(cells).collect());
    }
    s.push_str(&curve.markdown());
    if let Some(p) = &r.prequential {
        prequential_section(&mut s, p);
    }
    s
}

/// The prequential protocol's table: each contender's pooled RMSE and NLPD
/// beside the refitted baseline's.
fn prequential_section(s: &mut String, p: &crate::execute::prequential::Prequential) {
    let mut table = Table::new(&[
        "contender",
        "RMSE",
        "RMSE / refitted",
        "NLPD",
        "update p50 [µs]",
        "p95",
        "p99",
    ]);
    let reference = p.refitted.rmse;
    for score in std::iter::once(&p.refitted)
        .chain(&p.baselines)
        .chain(&p.learners)
    {
        let latency = |f: fn(&Latency) -> f64| {
            score
                .update_latency
                .as_ref()
                .map_or("–".into(), |l| format!("{:.1}", f(l)))
        };
        table.push(vec![
            score.label.clone(),
            format!("{:.6}", score.rmse),
            format!("{:.3}", score.rmse / reference),
            format!("{:.3}", score.nlpd),
            latency(|l| l.median_us),
            latency(|l| l.p95_us),
            latency(|l| l.p99_us),
        ]);
    }
    let _ = writeln!(
        s,
        "\n## Prequential\n\nThe training rows in time order, cut into {} blocks of {} rows; the {} samples of blocks 2…{} are scored. The baseline is refitted on blocks 1…k−1 to predict block k (refits took {:.1} s in all); each online learner predicts every sample before learning it, from an empty model. Pooled over the outputs; `plots/prequential.svg` draws the RMSE pooled up to each block.\n\n{}",
        p.blocks,
        p.block_rows,
        p.scored,
        p.blocks,
        p.refits.iter().map(|r| r.seconds()).sum::<f64>(),
        table.markdown()
    );
    refits_section(s, p);
}

/// Each refit's cold and warm fit: their log marginal likelihoods,
/// evaluations and seconds, and which one predicted.
fn refits_section(s: &mut String, p: &crate::execute::prequential::Prequential) {
    let records = p.refits.iter().flat_map(|r| r.cold.iter().chain(&r.warm));
    if records.clone().all(|f| f.lml.is_none()) {
        return;
    }
    let mut table = Table::new(&[
        "prefix rows",
        "LML cold",
        "LML warm",
        "cold − warm",
        "kept",
        "evaluations cold / warm",
        "seconds cold / warm",
    ]);
    let show = |f: &Option<FitRecord>, what: fn(&FitRecord) -> String| {
        f.as_ref().map_or("–".to_string(), what)
    };
    for r in &p.refits {
        let difference = match (
            r.cold.as_ref().and_then(|f| f.lml),
            r.warm.as_ref().and_then(|f| f.lml),
        ) {
            (Some(c), Some(w)) => format!("{:+.2}", c - w),
            _ => "–".into(),
        };
        table.push(vec![
            r.rows.to_string(),
            show(&r.cold, |f| {
                f.lml.map_or("–".into(), |l| format!("{l:.2}"))
            }),
            show(&r.warm, |f| {
                f.lml.map_or("–".into(), |l| format!("{l:.2}"))
            }),
            difference,
            if r.kept_warm { "warm" } else { "cold" }.into(),
            format!(
                "{} / {}",
                show(&r.cold, |f| f
                    .evaluations
                    .map_or("–".into(), |e| e.to_string())),
                show(&r.warm, |f| f
                    .evaluations
                    .map_or("–".into(), |e| e.to_string()))
            ),
            format!(
                "{} / {}",
                show(&r.cold, |f| format!("{:.2}", f.seconds)),
                show(&r.warm, |f| format!("{:.2}", f.seconds))
            ),
        ]);
    }
    let _ = writeln!(
        s,
        "\nEach refit of the baseline: the cold fit starts from the start policy, the warm one from the previous refit's optimum alone (log marginal likelihood in standardised units; a positive difference means the warm start kept to a lower optimum).\n\n{}",
        table.markdown()
    );
}
