//! Tables over the runs of a sweep: Table I and Table II in the paper's
//! layouts (mean ± std over seeds for every setting), an ablation table per
//! swept dimension (best per column in bold, ratios to the exact-GP row of
//! the same run), and the frames-versus-RMSE figure.

use std::collections::BTreeMap;

use crate::execute::records::{RegressorMetrics, RunRecord, SchemeMetrics};
use crate::plan::PlanFile;
use crate::report::table::Table;

/// Mean and sample standard deviation of a set of values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one value).
    pub std: f64,
    /// Number of values.
    pub n: usize,
}

impl Stat {
    /// The statistics of `values` (`None` when empty or not all finite).
    pub fn of(values: &[f64]) -> Option<Self> {
        let n = values.len();
        if n == 0 || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Some(Self { mean, std, n })
    }

    fn show(&self, digits: usize) -> String {
        if self.n > 1 {
            format!("{:.*} ± {:.*}", digits, self.mean, digits, self.std)
        } else {
            format!("{:.*}", digits, self.mean)
        }
    }
}

/// A run's setting: its swept values other than the seed.
fn setting(r: &RunRecord) -> String {
    if r.assignment.is_empty() {
        "–".to_string()
    } else {
        r.assignment
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Index of the first exact GP among a run's regressors.
fn exact_gp_row(r: &RunRecord) -> Option<usize> {
    r.config
        .regressors
        .iter()
        .position(|s| matches!(s, gpodo_regressors::RegressorSpec::ExactGp(_)))
}

/// Table I: each (setting, regressor) over seeds.
pub(crate) fn table_one(records: &[RunRecord]) -> Option<Table> {
    let mut groups: BTreeMap<(String, usize, String), Vec<&RunRecord>> = BTreeMap::new();
    let mut order: Vec<(String, usize, String)> = Vec::new();
    for r in records {
        for (i, m) in r.metrics.regressors.iter().enumerate() {
            let key = (setting(r), i, m.label.clone());
            if !groups.contains_key(&key) {
                order.push(key.clone());
            }
            groups.entry(key).or_default().push(r);
        }
    }
    if order.is_empty() {
        return None;
    }
    let mut table = Table::new(&[
        "setting",
        "regressor",
        "runs",
        "RMSE",
        "MAE",
        "NLPD",
        "95% coverage",
        "RMSE / exact GP",
    ])
    .with_csv(&[
        "setting",
        "regressor",
        "runs",
        "rmse_mean",
        "rmse_std",
        "mae_mean",
        "mae_std",
        "nlpd_mean",
        "coverage95_mean",
        "rmse_ratio_exact_gp_mean",
    ]);
    for key in order {
        let runs = &groups[&key];
        let (set, i, label) = key;
        let get = |f: &dyn Fn(&RegressorMetrics) -> f64| -> Vec<f64> {
            runs.iter().map(|r| f(&r.metrics.regressors[i])).collect()
        };
        let ratio: Vec<f64> = runs
            .iter()
            .filter_map(|r| {
                let b = exact_gp_row(r)?;
                Some(r.metrics.regressors[i].rmse / r.metrics.regressors[b].rmse)
            })
            .collect();
        let (rmse, mae, nlpd, cov, ratio) = (
            Stat::of(&get(&|m| m.rmse)),
            Stat::of(&get(&|m| m.mae)),
            Stat::of(&get(&|m| m.nlpd)),
            Stat::of(&get(&|m| m.coverage95)),
            Stat::of(&ratio),
        );
        let show = |s: Option<Stat>, d: usize| s.map_or("–".into(), |s| s.show(d));
        table.push(vec![
            set.clone(),
            label.clone(),
            runs.len().to_string(),
            show(rmse, 6),
            show(mae, 6),
            show(nlpd, 3),
            show(cov, 3),
            show(ratio, 3),
        ]);
        let num = |s: Option<Stat>, std: bool| {
            s.map_or(String::new(), |s| {
                format!("{}", if std { s.std } else { s.mean })
            })
        };
        table.push_csv(vec![
            set,
            label,
            runs.len().to_string(),
            num(rmse, false),
            num(rmse, true),
            num(mae, false),
            num(mae, true),
            num(nlpd, false),
            num(cov, false),
            num(ratio, false),
        ]);
    }
    Some(table)
}

/// Table II: each (setting, scheme, traverse) over seeds.
pub(crate) fn table_two(records: &[RunRecord]) -> Option<Table> {
    let mut groups: BTreeMap<(String, usize), Vec<(&RunRecord, usize)>> = BTreeMap::new();
    let mut order: Vec<(String, usize)> = Vec::new();
    let mut names: BTreeMap<(String, usize), (String, String)> = BTreeMap::new();
    for r in records {
        for (i, m) in r.metrics.schemes.iter().enumerate() {
            let key = (setting(r), i);
            if !groups.contains_key(&key) {
                order.push(key.clone());
                names.insert(key.clone(), (m.label.clone(), m.traverse.clone()));
            }
            groups.entry(key).or_default().push((r, i));
        }
    }
    if order.is_empty() {
        return None;
    }
    let mut table = Table::new(&[
        "setting",
        "scheme",
        "run",
        "runs",
        "#Frames",
        "#Keyframes",
        "RMSE [m]",
        "Max E. [m]",
        "Final E. [m]",
        "Travel Distance E. [%]",
        "frames / first",
        "RMSE / first",
        "VO losses",
        "drift since look, p95 [m]",
        "RPE 1 m [m]",
        "compute [ms/m]",
    ])
    .with_csv(&[
        "setting",
        "scheme",
        "traverse",
        "runs",
        "frames_mean",
        "frames_std",
        "keyframes_mean",
        "rmse_m_mean",
        "rmse_m_std",
        "max_error_m_mean",
        "final_error_m_mean",
        "travel_distance_error_percent_mean",
        "frames_ratio_first_mean",
        "rmse_ratio_first_mean",
        "tracking_losses_mean",
        "drift_since_look_p95_m_mean",
        "drift_since_look_max_m_mean",
        "rpe_1m_m_mean",
        "rpe_10s_m_mean",
        "cpu_ms_per_m_mean",
        "rmse_keyframes_m_mean",
        "rmse_processed_m_mean",
        "rmse_between_m_mean",
    ]);
    for key in order {
        let runs = &groups[&key];
        let (label, traverse) = names[&key].clone();
        let get = |f: &dyn Fn(&SchemeMetrics) -> f64| -> Vec<f64> {
            runs.iter()
                .map(|(r, i)| f(&r.metrics.schemes[*i]))
                .collect()
        };
        let first = |f: &dyn Fn(&SchemeMetrics) -> f64| -> Vec<f64> {
            runs.iter()
                .filter_map(|(r, i)| {
                    let m = &r.metrics.schemes[*i];
                    let f0 = r
                        .metrics
                        .schemes
                        .iter()
                        .find(|s| s.traverse == m.traverse)?;
                    Some(f(m) / f(f0).max(f64::MIN_POSITIVE))
                })
                .collect()
        };
        let stats = [
            Stat::of(&get(&|m| m.frames as f64)),
            Stat::of(&get(&|m| m.keyframes as f64)),
            Stat::of(&get(&|m| m.rmse_m)),
            Stat::of(&get(&|m| m.max_error_m)),
            Stat::of(&get(&|m| m.final_error_m)),
            Stat::of(&get(&|m| m.travel_distance_error_percent)),
            Stat::of(&first(&|m| m.frames as f64)),
            Stat::of(&first(&|m| m.rmse_m)),
            Stat::of(&get(&|m| m.tracking_losses as f64)),
            Stat::of(&get(&|m| m.rover.drift_since_look_p95_m)),
            Stat::of(&get(&|m| m.rover.rpe_1m_m)),
            Stat::of(&get(&|m| m.rover.cpu_ms_per_m)),
        ];
        let digits = [0, 0, 3, 3, 3, 2, 2, 2, 1, 3, 3, 0];
        let csv_only = [
            Stat::of(&get(&|m| m.rover.drift_since_look_max_m)),
            Stat::of(&get(&|m| m.rover.rpe_10s_m)),
            Stat::of(&get(&|m| m.rover.rmse_keyframes_m)),
            Stat::of(&get(&|m| m.rover.rmse_processed_m)),
            Stat::of(&get(&|m| m.rover.rmse_between_m)),
        ];
        let mut row = vec![
            key.0.clone(),
            label.clone(),
            traverse.clone(),
            runs.len().to_string(),
        ];
        row.extend(
            stats
                .iter()
                .zip(digits)
                .map(|(s, d)| s.map_or("–".into(), |s| s.show(d))),
        );
        table.push(row);
        let mean = |s: &Option<Stat>| s.map_or(String::new(), |s| s.mean.to_string());
        let std = |s: &Option<Stat>| s.map_or(String::new(), |s| s.std.to_string());
        table.push_csv(vec![
            key.0,
            label,
            traverse,
            runs.len().to_string(),
            mean(&stats[0]),
            std(&stats[0]),
            mean(&stats[1]),
            mean(&stats[2]),
            std(&stats[2]),
            mean(&stats[3]),
            mean(&stats[4]),
            mean(&stats[5]),
            mean(&stats[6]),
            mean(&stats[7]),
            mean(&stats[8]),
            mean(&stats[9]),
            mean(&csv_only[0]),
            mean(&stats[10]),
            mean(&csv_only[1]),
            mean(&stats[11]),
            mean(&csv_only[2]),
            mean(&csv_only[3]),
            mean(&csv_only[4]),
        ]);
    }
    Some(table)
}

/// The columns of an ablation table: (name, per-run value, lower is
/// better).
type Column = (String, Box<dyn Fn(&RunRecord) -> Option<f64>>, bool);

fn ablation_columns(records: &[RunRecord]) -> Vec<Column> {
    let mut columns: Vec<Column> = Vec::new();
    let mut regressors: Vec<(usize, String)> = Vec::new();
    let mut schemes: Vec<(usize, String)> = Vec::new();
    for r in records {
        for (i, m) in r.metrics.regressors.iter().enumerate() {
            if !regressors.iter().any(|(j, _)| *j == i) {
                regressors.push((i, m.label.clone()));
            }
        }
        for (i, m) in r.metrics.schemes.iter().enumerate() {
            if !schemes.iter().any(|(j, _)| *j == i) {
                schemes.push((i, m.label.clone()));
            }
        }
    }
    for (i, _) in &regressors {
        let i = *i;
        columns.push((
            format!("regressor {i} RMSE"),
            Box::new(move |r: &RunRecord| r.metrics.regressors.get(i).map(|m| m.rmse)),
            true,
        ));
        columns.push((
            format!("regressor {i} RMSE / exact GP"),
            Box::new(move |r: &RunRecord| {
                let b = exact_gp_row(r)?;
                Some(r.metrics.regressors.get(i)?.rmse / r.metrics.regressors.get(b)?.rmse)
            }),
            true,
        ));
    }
    for (i, label) in &schemes {
        let i = *i;
        columns.push((
            format!("{label}: frames"),
            Box::new(move |r: &RunRecord| r.metrics.schemes.get(i).map(|m| m.frames as f64)),
            true,
        ));
        columns.push((
            format!("{label}: RMSE [m]"),
            Box::new(move |r: &RunRecord| r.metrics.schemes.get(i).map(|m| m.rmse_m)),
            true,
        ));
    }
    // Drop the ratio columns when no run has an exact GP.
    columns.retain(|(name, f, _)| {
        !name.ends_with("/ exact GP") || records.iter().any(|r| f(r).is_some())
    });
    columns
}

/// One ablation table per swept dimension.
pub(crate) fn ablations(records: &[RunRecord], plan: Option<&PlanFile>) -> Vec<(String, Table)> {
    let Some(plan) = plan else {
        return Vec::new();
    };
    let columns = ablation_columns(records);
    let mut out = Vec::new();
    for dim in &plan.dimensions {
        let mut values: Vec<String> = Vec::new();
        for r in records {
            if let Some(v) = r.assignment.get(&dim.name)
                && !values.contains(v)
            {
                values.push(v.clone());
            }
        }
        let cells: Vec<Vec<Option<Stat>>> = values
            .iter()
            .map(|v| {
                let runs: Vec<&RunRecord> = records
                    .iter()
                    .filter(|r| r.assignment.get(&dim.name) == Some(v))
                    .collect();
                columns
                    .iter()
                    .map(|(_, f, _)| {
                        let xs: Vec<f64> = runs.iter().filter_map(|r| f(r)).collect();
                        Stat::of(&xs)
                    })
                    .collect()
            })
            .collect();
        // Best (lowest mean) per column, in bold, where the column varies.
        let best: Vec<Option<usize>> = (0..columns.len())
            .map(|c| {
                let means: Vec<(usize, f64)> = (0..values.len())
                    .filter_map(|v| cells[v][c].map(|s| (v, s.mean)))
                    .collect();
                let (lo, hi) = means
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (_, m)| {
                        (a.min(*m), b.max(*m))
                    });
                if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
                    return None;
                }
                means
                    .into_iter()
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(v, _)| v)
            })
            .collect();
        let mut table = Table::new(
            &std::iter::once(dim.name.clone())
                .chain(columns.iter().map(|(n, _, _)| n.clone()))
                .collect::<Vec<_>>(),
        )
        .with_csv(
            &std::iter::once(dim.name.clone())
                .chain(
                    columns
                        .iter()
                        .flat_map(|(n, _, _)| [format!("{n} mean"), format!("{n} std")]),
                )
                .collect::<Vec<_>>(),
        );
        for (v, value) in values.iter().enumerate() {
            let mut row = vec![format!("`{value}`")];
            let mut csv = vec![value.clone()];
            for (c, cell) in cells[v].iter().enumerate() {
                let digits = if columns[c].0.contains("frames") {
                    0
                } else {
                    4
                };
                let text = cell.map_or("–".into(), |s| s.show(digits));
                row.push(if best[c] == Some(v) && values.len() > 1 {
                    format!("**{text}**")
                } else {
                    text
                });
                csv.push(cell.map_or(String::new(), |s| s.mean.to_string()));
                csv.push(cell.map_or(String::new(), |s| s.std.to_string()));
            }
            table.push(row);
            table.push_csv(csv);
        }
        out.push((dim.name.clone(), table));
    }
    out
}
