//! The report of a sweep, from its records (`gpodo report results/<name>`,
//! also run at the end of every sweep): shards merged, missing and
//! duplicate runs detected; Table I and Table II in the paper's layouts
//! (mean ± std over seeds for every setting); an ablation table for each
//! swept dimension (mean ± std over the runs with each value, best per
//! column in bold, ratios to the exact-GP row of the same run); a
//! frames-versus-RMSE figure; and every table as CSV under `tables/`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::execute::records::{RecordError, RunRecord, read_records, record_files};
use crate::output::write_atomically;
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

/// The merged records of a results folder.
#[derive(Debug, Clone, PartialEq)]
pub struct MergedRecords {
    /// The plan, when `plan.json` is there.
    pub plan: Option<PlanFile>,
    /// One record per key, in plan order.
    pub records: Vec<RunRecord>,
    /// Keys recorded more than once, with the files holding them.
    pub duplicates: Vec<(String, Vec<PathBuf>)>,
    /// Planned keys with no record.
    pub missing: Vec<String>,
    /// The record files read.
    pub files: Vec<PathBuf>,
}

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Reading records failed.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// Reading the plan or writing the report failed.
    #[error("{}: {detail}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        detail: String,
    },
    /// There is nothing to report.
    #[error("{}: no run records (runs.jsonl or runs.<i>.jsonl)", dir.display())]
    Empty {
        /// The folder.
        dir: PathBuf,
    },
}

/// Reads and merges every record file of `dir`.
///
/// # Errors
/// [`ReportError`].
pub fn merge_records(dir: &Path) -> Result<MergedRecords, ReportError> {
    let files = record_files(dir).map_err(|e| ReportError::Io {
        path: dir.to_path_buf(),
        detail: e.to_string(),
    })?;
    let plan_path = dir.join("plan.json");
    let plan: Option<PlanFile> = match std::fs::read_to_string(&plan_path) {
        Ok(text) => Some(serde_json::from_str(&text).map_err(|e| ReportError::Io {
            path: plan_path.clone(),
            detail: e.to_string(),
        })?),
        Err(_) => None,
    };
    let mut by_key: BTreeMap<String, (RunRecord, Vec<PathBuf>)> = BTreeMap::new();
    for file in &files {
        for record in read_records(file)? {
            by_key
                .entry(record.key.clone())
                .or_insert_with(|| (record, Vec::new()))
                .1
                .push(file.clone());
        }
    }
    let duplicates = by_key
        .iter()
        .filter(|(_, (_, files))| files.len() > 1)
        .map(|(k, (_, files))| (k.clone(), files.clone()))
        .collect();
    let missing = plan
        .as_ref()
        .map(|p| {
            p.keys
                .iter()
                .filter(|k| !by_key.contains_key(*k))
                .cloned()
                .collect()
        })
        .unwrap_or_default();
    let order: BTreeMap<&str, usize> = plan
        .as_ref()
        .map(|p| {
            p.keys
                .iter()
                .enumerate()
                .map(|(i, k)| (k.as_str(), i))
                .collect()
        })
        .unwrap_or_default();
    let mut records: Vec<RunRecord> = by_key.into_values().map(|(r, _)| r).collect();
    records.sort_by_key(|r| {
        (
            order.get(r.key.as_str()).copied().unwrap_or(r.index),
            r.index,
        )
    });
    Ok(MergedRecords {
        plan,
        records,
        duplicates,
        missing,
        files,
    })
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
fn table_one(records: &[RunRecord]) -> Option<Table> {
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
        let get = |f: &dyn Fn(&crate::execute::records::RegressorMetrics) -> f64| -> Vec<f64> {
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
fn table_two(records: &[RunRecord]) -> Option<Table> {
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
    ]);
    for key in order {
        let runs = &groups[&key];
        let (label, traverse) = names[&key].clone();
        let get = |f: &dyn Fn(&crate::execute::records::SchemeMetrics) -> f64| -> Vec<f64> {
            runs.iter()
                .map(|(r, i)| f(&r.metrics.schemes[*i]))
                .collect()
        };
        let first = |f: &dyn Fn(&crate::execute::records::SchemeMetrics) -> f64| -> Vec<f64> {
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
        ];
        let digits = [0, 0, 3, 3, 3, 2, 2, 2, 1];
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
fn ablations(records: &[RunRecord], plan: Option<&PlanFile>) -> Vec<(String, Table)> {
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

/// The frames-versus-RMSE figure of Table II's rows.
fn tradeoff_svg(records: &[RunRecord]) -> Option<String> {
    let table = table_two(records)?;
    let points: Vec<(String, f64, f64, f64)> = table
        .csv_rows()
        .iter()
        .filter_map(|row| {
            let frames: f64 = row.get(4)?.parse().ok()?;
            let rmse: f64 = row.get(7)?.parse().ok()?;
            let std: f64 = row.get(8)?.parse().unwrap_or(0.0);
            let label = if row[0] == "–" {
                row[1].clone()
            } else {
                format!("{} [{}]", row[1], row[0])
            };
            Some((label, frames, rmse, std))
        })
        .collect();
    crate::report::plots::tradeoff_svg(&points).ok()
}

/// What `write_sweep_report` wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepReport {
    /// The report.
    pub markdown: PathBuf,
    /// Runs reported.
    pub runs: usize,
    /// Planned runs without a record.
    pub missing: usize,
    /// Keys recorded more than once.
    pub duplicates: usize,
}

/// Writes the sweep report of `dir` to `dir/<file_name>` and the tables to
/// `dir/tables/`.
///
/// # Errors
/// [`ReportError`].
pub fn write_sweep_report(dir: &Path, file_name: &str) -> Result<SweepReport, ReportError> {
    let merged = merge_records(dir)?;
    if merged.records.is_empty() {
        return Err(ReportError::Empty {
            dir: dir.to_path_buf(),
        });
    }
    let io = |path: &Path, e: std::io::Error| ReportError::Io {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let tables_dir = dir.join("tables");
    std::fs::create_dir_all(&tables_dir).map_err(|e| io(&tables_dir, e))?;
    let records = &merged.records;
    let name = merged
        .plan
        .as_ref()
        .map(|p| p.name.clone())
        .unwrap_or_else(|| records[0].config.name.clone());
    let mut s = String::new();
    let _ = writeln!(s, "# Sweep `{name}`\n");
    if let Some(d) = &records[0].config.description {
        let _ = writeln!(s, "{}\n", d.trim());
    }
    let versions: BTreeSet<&str> = records.iter().map(|r| r.code_version.as_str()).collect();
    let _ = writeln!(
        s,
        "{} runs from {} record file(s); code {}.",
        records.len(),
        merged.files.len(),
        versions
            .into_iter()
            .map(|v| format!("`{v}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(plan) = &merged.plan {
        let _ = writeln!(
            s,
            "Plan: {} runs{}{}.",
            plan.keys.len(),
            if plan.dimensions.is_empty() {
                String::new()
            } else {
                format!(
                    ", swept: {}",
                    plan.dimensions
                        .iter()
                        .map(|d| format!("`{}` ({} values)", d.name, d.values.len()))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            },
            if plan.replicates.is_empty() {
                String::new()
            } else {
                format!(", seeds {:?} (sweep seed {})", plan.replicates, plan.seed)
            }
        );
    }
    if !merged.missing.is_empty() {
        let _ = writeln!(
            s,
            "\n**Incomplete: {} planned run(s) have no record** (run the missing shards, or `gpodo run --resume`): {}",
            merged.missing.len(),
            merged
                .missing
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !merged.duplicates.is_empty() {
        let _ = writeln!(
            s,
            "\n**{} run(s) recorded more than once** (the first record is used): {}",
            merged.duplicates.len(),
            merged
                .duplicates
                .iter()
                .map(|(k, files)| format!(
                    "`{k}` in {}",
                    files
                        .iter()
                        .map(|f| f.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    s.push('\n');
    let write_table = |file: &str, table: &Table| -> Result<(), ReportError> {
        let path = tables_dir.join(file);
        write_atomically(&path, table.csv_text().as_bytes()).map_err(|e| io(&path, e))
    };
    if let Some(t) = table_one(records) {
        let _ = writeln!(
            s,
            "## Table I — residual prediction\n\nPooled over the outputs, on the test rows; mean ± std over the runs of each setting (seeds). The last column divides by the exact GP of the same run.\n\n{}",
            t.markdown()
        );
        write_table("table1.csv", &t)?;
    }
    if let Some(t) = table_two(records) {
        let _ = writeln!(
            s,
            "## Table II — localisation and mapping\n\nMean ± std over the runs of each setting (seeds); ratios to the first scheme of the same run.\n\n{}",
            t.markdown()
        );
        write_table("table2.csv", &t)?;
        if let Some(svg) = tradeoff_svg(records) {
            let plots = dir.join("plots");
            std::fs::create_dir_all(&plots).map_err(|e| io(&plots, e))?;
            let path = plots.join("tradeoff.svg");
            write_atomically(&path, svg.as_bytes()).map_err(|e| io(&path, e))?;
            let _ = writeln!(
                s,
                "Frames processed against trajectory RMSE: `plots/tradeoff.svg`.\n"
            );
        }
    }
    for (i, (dim, table)) in ablations(records, merged.plan.as_ref())
        .into_iter()
        .enumerate()
    {
        let _ = writeln!(
            s,
            "## Ablation: `{dim}`\n\nMean ± std over every run with each value (other swept values and seeds pooled); best (lowest) in bold. Regressors are numbered as in the experiment.\n\n{}",
            table.markdown()
        );
        write_table(&format!("ablation_{i}.csv"), &table)?;
    }
    let markdown = dir.join(file_name);
    write_atomically(&markdown, s.as_bytes()).map_err(|e| io(&markdown, e))?;
    Ok(SweepReport {
        markdown,
        runs: records.len(),
        missing: merged.missing.len(),
        duplicates: merged.duplicates.len(),
    })
}
