//! Writes an experiment's `report.md` (human-readable, the paper's Table I
//! layout) and `metrics.json` (everything, machine-readable). Files are
//! written to a temporary name and renamed, so a crash never leaves a
//! half-written report.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::calibration::ResidualStatistics;
use crate::config::DatasetSpec;
use crate::pipeline::{ExperimentResults, RegressorResult};

/// Writes `contents` to `path` atomically (temporary file + rename).
///
/// # Errors
/// The I/O error, with the path.
pub fn write_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension(format!(
        "{}.tmp",
        path.extension().and_then(|e| e.to_str()).unwrap_or("")
    ));
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path)
}

/// Writes `report.md` and `metrics.json` into `dir` (created if needed) and
/// returns their paths.
///
/// # Errors
/// Any I/O or serialisation error.
pub fn write_report(results: &ExperimentResults, dir: &Path) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(dir)?;
    let md = dir.join("report.md");
    let json = dir.join("metrics.json");
    write_atomically(&json, serde_json::to_string_pretty(results)?.as_bytes())?;
    write_atomically(&md, markdown(results).as_bytes())?;
    for (name, rows) in [
        ("residuals_train.csv", &results.train_rows),
        ("residuals_test.csv", &results.test_rows),
    ] {
        if let Some(rows) = rows {
            write_atomically(&dir.join(name), residual_csv(rows).as_bytes())?;
        }
    }
    Ok((md, json))
}

/// A residual dataset as CSV: input columns, then target columns, full
/// precision (the format `kind: residual_table` reads back).
pub fn residual_csv(data: &gpodo_traits::ResidualDataset) -> String {
    let mut s = data.input_names.join(",");
    for t in &data.target_names {
        s.push(',');
        s.push_str(t);
    }
    s.push('\n');
    for (x, y) in data.inputs.rows().zip(data.targets.rows()) {
        let cells: Vec<String> = x.iter().chain(y).map(|v| v.to_string()).collect();
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

fn mm(v: f64) -> String {
    format!("{:.2}", v * 1e3)
}

fn opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{:.*}", digits, v * scale))
}

/// The Markdown report.
pub fn markdown(r: &ExperimentResults) -> String {
    let mut s = String::new();
    let c = &r.config;
    let _ = writeln!(s, "# Experiment `{}`\n", c.name);
    if let Some(d) = &c.description {
        let _ = writeln!(s, "{}\n", d.trim());
    }
    let _ = writeln!(
        s,
        "Data: {}. Training rows: {}, test rows: {}. Motion model: {}. Code: `{}`. Wall time: {:.1} s.\n",
        r.dataset.source,
        r.dataset.n_train,
        r.dataset.n_test,
        r.motion_model.as_deref().unwrap_or("none (residual table)"),
        r.code_version,
        r.duration_secs
    );
    runs_section(&mut s, r);
    table_one(&mut s, r);
    hyperparameter_section(&mut s, r);
    dead_reckoning_section(&mut s, r);
    statistics_section(&mut s, r);
    s
}

fn runs_section(s: &mut String, r: &ExperimentResults) {
    if r.dataset.train_runs.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Runs\n\n| run | role | samples | duration [s] | path [m] |\n|---|---|---:|---:|---:|"
    );
    for (role, runs) in [
        ("train", &r.dataset.train_runs),
        ("test", &r.dataset.test_runs),
    ] {
        for run in runs {
            let _ = writeln!(
                s,
                "| {} | {role} | {} | {:.1} | {:.2} |",
                run.name, run.samples, run.duration_secs, run.path_length_m
            );
        }
    }
    if let Some(slope) = r.dataset.terrain_max_slope_deg {
        let _ = writeln!(s, "\nSteepest terrain slope: {slope:.1}°.");
    }
    s.push('\n');
}

fn table_one(s: &mut String, r: &ExperimentResults) {
    let targets = r.dataset.target_names.join(", ");
    let units = match (&r.config.dataset, r.config.residuals.window_secs) {
        (DatasetSpec::ResidualTable { .. }, _) => "in the table's target units".to_string(),
        (_, Some(w)) => format!("m/s ({w}-s mean body-velocity residuals)"),
        (_, None) => "m/s (per-step body-velocity residuals)".to_string(),
    };
    let _ = writeln!(
        s,
        "## Table I — residual prediction on the test rows\n\nRMSE and MAE pooled over the outputs ({targets}), in the paper's layout; {units}.\n\n| Regressor | RMSE | MAE |\n|---|---:|---:|"
    );
    for reg in &r.regressors {
        let e = &reg.evaluation.pooled;
        let _ = writeln!(s, "| {} | {:.6} | {:.6} |", reg.label, e.rmse, e.mae);
    }
    let _ = writeln!(
        s,
        "\nPer output (× 1000), predictive quality and fit (log marginal likelihood on the standardised training rows; evaluations of the objective and its gradient):\n\n| Regressor | RMSE per output | MAE per output | NLPD | 95% coverage | fit [s] | LML | evaluations | jitter |\n|---|---|---|---:|---:|---:|---:|---:|---:|"
    );
    for reg in &r.regressors {
        let per = &reg.evaluation.per_output;
        let rmse: Vec<String> = per.iter().map(|p| mm(p.rmse)).collect();
        let mae: Vec<String> = per.iter().map(|p| mm(p.mae)).collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {} | {} | {} |",
            reg.label,
            rmse.join(" / "),
            mae.join(" / "),
            reg.evaluation.pooled.nlpd,
            reg.evaluation.pooled.coverage95,
            reg.fit.duration_secs,
            opt(reg.fit.objective, 1.0, 2),
            reg.fit.evaluations.map_or("–".into(), |e| e.to_string()),
            reg.fit.jitter.map_or("–".into(), |j| format!("{j:.1e}")),
        );
    }
    s.push('\n');
}

/// How many of the shortest lengthscales to list per model.
const RELEVANT_INPUTS: usize = 6;

fn hyperparameter_section(s: &mut String, r: &ExperimentResults) {
    let fitted: Vec<&RegressorResult> = r
        .regressors
        .iter()
        .filter(|reg| !reg.fit.parameters.is_empty())
        .collect();
    if fitted.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Learned hyperparameters\n\nStandardised units. The shortest lengthscales mark the inputs the model relies on most (all values in `metrics.json`).\n\n| Regressor | noise variance | signal variance | shortest lengthscales |\n|---|---:|---:|---|"
    );
    for reg in fitted {
        let find = |suffix: &str| {
            reg.fit
                .parameters
                .iter()
                .filter(|(n, _)| {
                    n.ends_with(suffix) && !n.contains("linear") && !n.contains("white")
                })
                .map(|(_, v)| format!("{v:.3e}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut lengthscales: Vec<(&str, f64)> = reg
            .fit
            .parameters
            .iter()
            .filter_map(|(n, v)| {
                let start = n.find(".lengthscale[")?;
                Some((&n[start + ".lengthscale[".len()..n.len() - 1], *v))
            })
            .collect();
        lengthscales.sort_by(|a, b| a.1.total_cmp(&b.1));
        let shortest: Vec<String> = lengthscales
            .iter()
            .take(RELEVANT_INPUTS)
            .map(|(name, v)| format!("{name} {v:.2}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            reg.label,
            find("noise_variance"),
            find(".variance"),
            if shortest.is_empty() {
                "–".into()
            } else {
                shortest.join(", ")
            }
        );
    }
    s.push('\n');
}

fn dead_reckoning_section(s: &mut String, r: &ExperimentResults) {
    if r.dead_reckoning.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Parametric odometry alone on the test runs\n\nDead reckoning with the motion model from the first ground-truth pose.\n\n| run | distance [m] | final error [m] | max error [m] | travel distance error [%] |\n|---|---:|---:|---:|---:|"
    );
    for (name, d) in &r.dead_reckoning {
        let _ = writeln!(
            s,
            "| {name} | {:.2} | {:.3} | {:.3} | {:.2} |",
            d.distance_m, d.final_error_m, d.max_error_m, d.final_error_percent
        );
    }
    s.push('\n');
}

fn statistics_row(s: &mut String, label: &str, st: &ResidualStatistics) {
    let means: Vec<String> = st.mean_abs.iter().map(|v| mm(*v)).collect();
    let p95: Vec<String> = st.p95_abs.iter().map(|v| mm(*v)).collect();
    let _ = writeln!(
        s,
        "| {label} | {} | {} | {} | {} | {} | {} | {} | {} |",
        st.n_rows,
        means.join(" / "),
        p95.join(" / "),
        opt(st.moving_fraction, 100.0, 0),
        opt(st.mean_wheel_speed_moving_mps, 100.0, 2),
        opt(st.median_slip_ratio_x, 100.0, 1),
        opt(st.corr_abs_x_abs_pitch, 1.0, 2),
        opt(st.corr_abs_x_abs_roll, 1.0, 2),
    );
}

fn statistics_section(s: &mut String, r: &ExperimentResults) {
    let _ = writeln!(
        s,
        "## Residual statistics\n\nAbsolute residuals of the rows as used (mean and 95th percentile per output, × 1000: mm/s for velocity residuals); moving rows have a mean wheel speed above 5 mm/s; slip ratio = |residual x| / wheel speed on moving rows; correlations of |residual x| with |pitch| and |roll|.\n\n| rows | n | mean abs | p95 abs | moving [%] | wheel speed [cm/s] | median slip ratio x [%] | corr pitch | corr roll |\n|---|---:|---|---|---:|---:|---:|---:|---:|"
    );
    statistics_row(s, "train", &r.train_statistics);
    statistics_row(s, "test", &r.test_statistics);
    if let Some((name, st)) = &r.reference_statistics {
        statistics_row(s, &format!("reference `{name}`"), st);
        let ratios: Vec<String> = r
            .train_statistics
            .mean_abs
            .iter()
            .zip(&st.mean_abs)
            .map(|(a, b)| format!("{:.2}", a / b))
            .collect();
        let _ = writeln!(
            s,
            "\nMean |residual| ratio training rows / reference per output: {} (within a factor 1.5 means the simulated testbed's lessons should transfer).",
            ratios.join(" / ")
        );
    }
}
