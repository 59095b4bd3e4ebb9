//! Writes `bench.md` (tables with ratios to the baseline row) and
//! `bench.json` (everything measured), atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::bench::{BenchResults, BenchRow};
use crate::report::write_atomically;

/// Writes `bench.md` and `bench.json` into `dir` and returns their paths.
///
/// # Errors
/// Any I/O or serialisation error.
pub fn write_bench_report(r: &BenchResults, dir: &Path) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(dir)?;
    let md = dir.join("bench.md");
    let json = dir.join("bench.json");
    write_atomically(&json, serde_json::to_string_pretty(r)?.as_bytes())?;
    write_atomically(&md, bench_markdown(r).as_bytes())?;
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
    let _ = writeln!(
        s,
        "## Batch fit and prediction\n\nFit on all training rows; scores on the test rows (pooled over the outputs). Speed-up = baseline time / this time; RMSE ratio = this / baseline.\n\n| Regressor | fit [s] | fit speed-up | predict [µs/query] (median) | predict speed-up | batch predict [s] | RMSE | RMSE ratio | MAE | NLPD | 95% coverage |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for row in &r.rows {
        let e = &row.evaluation.pooled;
        let _ = writeln!(
            s,
            "| {} | {:.3} | {} | {:.1} | {} | {:.4} | {:.6} | {} | {:.6} | {:.3} | {:.3} |",
            row.label,
            row.fit.duration_secs,
            speedup(row.fit.duration_secs, b_fit),
            row.predict_latency.median_us,
            speedup(row.predict_latency.median_us, b_pred),
            row.batch_predict_secs,
            e.rmse,
            ratio(e.rmse, b_rmse),
            e.mae,
            e.nlpd,
            e.coverage95,
        );
    }
    s.push('\n');
    let online: Vec<&BenchRow> = r.rows.iter().filter(|row| row.online.is_some()).collect();
    if online.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "## Online learning\n\nOne prequential pass over the training rows in time order, from an empty model: each sample is predicted, then learned. Latencies per sample (µs); scores on the test rows after the pass.\n\n| Regressor | predict + update median | p95 | update median | RMSE after one pass | RMSE ratio | MAE | NLPD | 95% coverage |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for row in &online {
        let Some(o) = &row.online else { continue };
        let e = &o.evaluation.pooled;
        let _ = writeln!(
            s,
            "| {} | {:.1} | {:.1} | {:.1} | {:.6} | {} | {:.6} | {:.3} | {:.3} |",
            row.label,
            o.step_latency.median_us,
            o.step_latency.p95_us,
            o.update_latency.median_us,
            e.rmse,
            ratio(e.rmse, b_rmse),
            e.mae,
            e.nlpd,
            e.coverage95
        );
    }
    let _ = writeln!(
        s,
        "\n### Learning curve\n\nPooled test RMSE after every {} training samples{}.\n",
        c.bench.learning_curve_every,
        b_rmse.map_or(String::new(), |b| format!(" (baseline batch RMSE {b:.6})"))
    );
    let mut header = "| samples |".to_string();
    let mut rule = "|---:|".to_string();
    for row in &online {
        let _ = write!(header, " {} |", row.label);
        rule.push_str("---:|");
    }
    let _ = writeln!(s, "{header}\n{rule}");
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
        let mut line = format!("| {samples} |");
        for row in &online {
            let cell = row
                .online
                .as_ref()
                .and_then(|o| o.curve.get(k))
                .map_or("–".into(), |p| format!("{:.6}", p.rmse));
            let _ = write!(line, " {cell} |");
        }
        let _ = writeln!(s, "{line}");
    }
    s
}
