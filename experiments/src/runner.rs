//! Runs a sweep: the shared work once, then every run in parallel (rayon),
//! each appended to the record as it finishes; resumable; shardable for
//! cluster array jobs (`--shard i/N`, or Slurm's `SLURM_ARRAY_TASK_ID`
//! with the count the folder records; [`crate::util::shard`]), each shard
//! writing `runs.<i>.jsonl`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::config::ExperimentConfig;
use crate::error::PipelineError;
use crate::execute::records::{
    RecordError, RecordWriter, RunRecord, read_records, record_files, record_path,
};
use crate::execute::results::ExperimentResults;
use crate::execute::shared::{SharedCounts, SharedWork};
use crate::plan::{PlanFile, RunSpec, SweepPlan};
use crate::report::write_report;
use crate::util::output::{slug, write_atomically};
pub use crate::util::shard::{Shard, ShardError};
use indicatif::{
    MultiProgress, ParallelProgressIterator, ProgressBar, ProgressDrawTarget, ProgressStyle,
};
use rayon::prelude::*;

/// How to run a sweep.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Results folder (default `results/<name>`).
    pub out: Option<PathBuf>,
    /// Skip runs already recorded (in any record file of the folder).
    pub resume: bool,
    /// Start over when this shard's record file exists.
    pub force: bool,
    /// Run one slice (`--shard i/N`).
    pub shard: Option<Shard>,
    /// The Slurm array task this process is (`SLURM_ARRAY_TASK_ID`), which
    /// without `shard` runs that slice of the count the folder records.
    pub slurm_task: Option<usize>,
    /// No progress bar.
    pub quiet: bool,
}

/// Why a sweep could not run.
#[derive(Debug, thiserror::Error)]
pub enum RunnerError {
    /// Results exist and neither `--resume` nor `--force` was given.
    #[error("{} already holds runs; pass --resume to continue the sweep or --force to start it over", path.display())]
    ResultsExist {
        /// The record file.
        path: PathBuf,
    },
    /// The shard cannot be settled.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// Writing or reading records failed.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The shared work failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// The user stopped the run (Ctrl-C).
    #[error(
        "stopped: the runs finished before the stop are recorded; `gpodo run --resume` runs the rest"
    )]
    Stopped,
    /// Writing a run's report failed (the error names the file).
    #[error(transparent)]
    Report(anyhow::Error),
    /// Writing a file failed.
    #[error("writing {}: {source}", path.display())]
    Output {
        /// The file or folder.
        path: PathBuf,
        /// What failed.
        source: anyhow::Error,
    },
}

/// What a sweep did.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOutcome {
    /// The results folder.
    pub dir: PathBuf,
    /// Runs executed now.
    pub ran: usize,
    /// Runs skipped because they were recorded already.
    pub skipped: usize,
    /// Runs of other shards.
    pub other_shards: usize,
    /// Shared work done.
    pub counts: SharedCounts,
    /// Whether every run of the plan is now recorded (in any shard).
    pub complete: bool,
    /// Wall-clock time (s).
    pub duration_secs: f64,
    /// The runs of this invocation that failed, with their reasons (each
    /// recorded as failed; `--resume` runs them again).
    pub failed: Vec<(String, String)>,
}

/// The results folder of a plan.
pub fn results_dir(plan: &SweepPlan, options: &RunOptions) -> PathBuf {
    options
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(&plan.name))
}

/// Keys recorded as successful runs in any record file of `dir` (a failed
/// run's record does not count: `--resume` runs it again).
///
/// # Errors
/// [`RecordError`].
pub fn recorded_keys(dir: &Path) -> Result<BTreeSet<String>, RecordError> {
    let mut keys = BTreeSet::new();
    let files = record_files(dir).map_err(|source| RecordError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    for file in files {
        keys.extend(
            read_records(&file)?
                .into_iter()
                .filter(|r| r.failure.is_none())
                .map(|r| r.key),
        );
    }
    Ok(keys)
}

/// Sees each run's results as the run finishes (from the worker thread
/// that ran it, in any order).
pub type RunObserver<'a> = dyn Fn(&RunSpec, &ExperimentResults) + Sync + 'a;

/// Runs the plan (or this shard of it).
///
/// # Errors
/// [`RunnerError`]; runs finished before a failure stay recorded.
pub fn run_sweep(plan: &SweepPlan, options: &RunOptions) -> Result<SweepOutcome, RunnerError> {
    run_sweep_observed(plan, options, &|_, _| {})
}

/// Runs every run of the plan and writes nothing: the shared work once,
/// then the runs in parallel (rayon, on the pool the call is made from), as
/// [`run_sweep`] does; `observer` sees each run's results as it finishes
/// (they are not kept). Returns the runs that failed: their indices in the
/// plan and why.
///
/// # Errors
/// [`RunnerError::Pipeline`] when the shared work fails,
/// [`RunnerError::Stopped`] after [`crate::util::stop::request`].
pub fn run_in_memory(
    plan: &SweepPlan,
    observer: &RunObserver<'_>,
) -> Result<Vec<(usize, String)>, RunnerError> {
    let start = Instant::now();
    let configs: Vec<&ExperimentConfig> = plan.runs.iter().map(|r| &r.config).collect();
    let shared = SharedWork::build(&configs, None)?;
    plan.runs
        .par_iter()
        .map(|run| {
            if crate::util::stop::requested() {
                return Err(RunnerError::Stopped);
            }
            let results = shared.results(&run.config);
            if crate::util::stop::requested() {
                return Err(RunnerError::Stopped);
            }
            match results {
                Ok(mut results) => {
                    results.duration_secs = start.elapsed().as_secs_f64();
                    results.cpu_secs = crate::util::cpu::process_cpu_secs();
                    observer(run, &results);
                    Ok(None)
                }
                Err(e) => Ok(Some((run.index, e.to_string()))),
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|failed| failed.into_iter().flatten().collect())
}

/// [`run_sweep`], with `observer` seeing each run's results as it is
/// recorded.
///
/// # Errors
/// As [`run_sweep`].
pub fn run_sweep_observed(
    plan: &SweepPlan,
    options: &RunOptions,
    observer: &RunObserver<'_>,
) -> Result<SweepOutcome, RunnerError> {
    let start = Instant::now();
    let dir = results_dir(plan, options);
    let output = |path: &Path, e: anyhow::Error| RunnerError::Output {
        path: path.to_path_buf(),
        source: e,
    };
    std::fs::create_dir_all(&dir).map_err(|e| output(&dir, e.into()))?;
    let plan_path = dir.join("plan.json");
    let recorded_shards = recorded_plan(&plan_path).and_then(|p| p.shards);
    let shard = Shard::resolve(options.shard, options.slurm_task, recorded_shards)?;
    let record = record_path(&dir, shard.map(|s| s.index));
    let has_runs = std::fs::metadata(&record).is_ok_and(|m| m.len() > 0);
    if has_runs && !options.resume && !options.force {
        return Err(RunnerError::ResultsExist { path: record });
    }
    let plan_file = PlanFile {
        shards: shard.map(|s| s.count).or(recorded_shards),
        ..PlanFile::new(plan)
    };
    let plan_json =
        serde_json::to_string_pretty(&plan_file).map_err(|e| output(&plan_path, e.into()))?;
    write_atomically(&plan_path, plan_json.as_bytes()).map_err(|e| output(&plan_path, e.into()))?;
    let done = if options.resume {
        recorded_keys(&dir)?
    } else {
        BTreeSet::new()
    };
    let writer = RecordWriter::open(&record, options.resume)?;
    let mine: Vec<&RunSpec> = plan
        .runs
        .iter()
        .filter(|r| shard.is_none_or(|s| s.owns(r.index)))
        .collect();
    let todo: Vec<&RunSpec> = mine
        .iter()
        .copied()
        .filter(|r| !done.contains(&r.key))
        .collect();
    let single = plan.runs.len() == 1;
    let details = plan.outputs.run_details.unwrap_or(single);
    tracing::info!(
        runs = plan.runs.len(),
        this_shard = mine.len(),
        to_run = todo.len(),
        folder = %dir.display(),
        "{}",
        if single { "experiment" } else { "sweep" }
    );
    let configs: Vec<&ExperimentConfig> = todo.iter().map(|r| &r.config).collect();
    let multi = if options.quiet {
        MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
    } else {
        MultiProgress::new()
    };
    let shared = SharedWork::build(&configs, Some(&multi))?;
    if crate::util::stop::requested() {
        return Err(RunnerError::Stopped);
    }
    let bar = if options.quiet {
        ProgressBar::hidden()
    } else {
        let bar = multi.add(ProgressBar::new(todo.len() as u64));
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} ({eta} left) {msg}")
        {
            bar.set_style(style);
        }
        bar
    };
    // A run that fails is recorded with its reason and the others go on;
    // the failures are returned in the outcome.
    let failed = std::sync::Mutex::new(Vec::new());
    todo.par_iter()
        .progress_with(bar.clone())
        .try_for_each(|run| -> Result<(), RunnerError> {
            if crate::util::stop::requested() {
                return Err(RunnerError::Stopped);
            }
            let results = shared.results(&run.config);
            // A run the stop cut short records nothing.
            if crate::util::stop::requested() {
                return Err(RunnerError::Stopped);
            }
            let mut results = match results {
                Ok(r) => r,
                Err(e) => {
                    let reason = e.to_string();
                    tracing::warn!(run = %run.key, error = %reason, "run failed; recorded as failed");
                    writer.append(&RunRecord::failed(run, shared.code_version(), reason.clone()))?;
                    failed
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner)
                        .push((run.key.clone(), reason));
                    return Ok(());
                }
            };
            // A run's wall time: since the sweep started (shared work included).
            results.duration_secs = start.elapsed().as_secs_f64();
            results.cpu_secs = crate::util::cpu::process_cpu_secs();
            writer.append(&RunRecord::new(run, &results))?;
            observer(run, &results);
            if details {
                let run_dir = if single {
                    dir.clone()
                } else {
                    dir.join("runs").join(slug(&run.key))
                };
                write_report(&results, &run_dir, plan.outputs.plots)
                    .map_err(RunnerError::Report)?;
            }
            Ok(())
        })?;
    bar.finish_and_clear();
    let recorded = recorded_keys(&dir)?;
    let complete = plan.runs.iter().all(|r| recorded.contains(&r.key));
    Ok(SweepOutcome {
        dir,
        ran: todo.len(),
        skipped: mine.len() - todo.len(),
        other_shards: plan.runs.len() - mine.len(),
        counts: shared.counts(),
        complete,
        failed: failed
            .into_inner()
            .unwrap_or_else(std::sync::PoisonError::into_inner),
        duration_secs: start.elapsed().as_secs_f64(),
    })
}

/// The `plan.json` an earlier run of the folder wrote, if it can be read.
fn recorded_plan(path: &Path) -> Option<PlanFile> {
    let text = std::fs::read_to_string(path).ok()?;
    serde_json::from_str(&text).ok()
}
