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
use crate::plan::PlanFile;
use crate::report::aggregate::{ablations, table_one, table_two};
use crate::report::curves_section::curves_section;
use crate::report::floor::floor_section;
use crate::report::sensitivity::sensitivity_section;
use crate::report::sensitivity_plot::sensitivity_svg;
use crate::report::table::Table;
use crate::report::tradeoff_plot::records_tradeoff_svg;
use crate::report::verdict_section::verdict_section;
use crate::util::output::write_atomically;

pub use crate::report::aggregate::Stat;

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
    /// Keys whose every record is a failure, with the last reason.
    pub failed: Vec<(String, String)>,
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
    // Failed runs are kept apart; a successful record of the same key
    // (from `--resume`) supersedes them.
    let mut failures: BTreeMap<String, String> = BTreeMap::new();
    for file in &files {
        for record in read_records(file)? {
            if let Some(reason) = &record.failure {
                failures.insert(record.key.clone(), reason.clone());
                continue;
            }
            by_key
                .entry(record.key.clone())
                .or_insert_with(|| (record, Vec::new()))
                .1
                .push(file.clone());
        }
    }
    let failed: Vec<(String, String)> = failures
        .into_iter()
        .filter(|(k, _)| !by_key.contains_key(k))
        .collect();
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
                .filter(|k| !by_key.contains_key(*k) && !failed.iter().any(|(f, _)| f == *k))
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
        failed,
        files,
    })
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
    /// Runs recorded only as failed.
    pub failed: usize,
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
    let mut s = String::new();
    write_header(&mut s, &merged);
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
        if let Some(svg) = records_tradeoff_svg(records) {
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
    let bootstrap_seed = merged.plan.as_ref().map_or(0, |p| p.seed);
    if let Some((markdown, table)) = verdict_section(records, bootstrap_seed) {
        s.push_str(&markdown);
        write_table("verdict.csv", &table)?;
    }
    if let Some((markdown, table)) = floor_section(records, bootstrap_seed) {
        s.push_str(&markdown);
        write_table("floor.csv", &table)?;
    }
    if let Some((markdown, table, effects)) = sensitivity_section(records, bootstrap_seed) {
        s.push_str(&markdown);
        write_table("sensitivity.csv", &table)?;
        match sensitivity_svg(&effects) {
            Ok(svg) => {
                let plots = dir.join("plots");
                std::fs::create_dir_all(&plots).map_err(|e| io(&plots, e))?;
                let path = plots.join("sensitivity.svg");
                write_atomically(&path, svg.as_bytes()).map_err(|e| io(&path, e))?;
            }
            Err(e) => {
                let _ = writeln!(s, "(The figure could not be drawn: {e}.)\n");
            }
        }
    }
    if let Some(section) = curves_section(records, bootstrap_seed) {
        s.push_str(&section.markdown);
        for (file, table) in &section.tables {
            write_table(file, table)?;
        }
        let plots = dir.join("plots");
        std::fs::create_dir_all(&plots).map_err(|e| io(&plots, e))?;
        for (file, svg) in &section.figures {
            let path = plots.join(file);
            write_atomically(&path, svg.as_bytes()).map_err(|e| io(&path, e))?;
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
        failed: merged.failed.len(),
    })
}

/// The report's heading and what it was made from: the runs, their code,
/// the plan, and the runs missing, failed or recorded twice.
fn write_header(s: &mut String, merged: &MergedRecords) {
    let records = &merged.records;
    let name = merged
        .plan
        .as_ref()
        .map(|p| p.name.clone())
        .unwrap_or_else(|| records[0].config.name.clone());
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
    if !merged.failed.is_empty() {
        let _ = writeln!(
            s,
            "\n**{} run(s) failed** (`gpodo run --resume` runs them again):",
            merged.failed.len()
        );
        for (key, reason) in &merged.failed {
            let first_line = reason.lines().next().unwrap_or_default();
            let _ = writeln!(s, "- `{key}`: {first_line}");
        }
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
}
