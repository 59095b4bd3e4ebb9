//! The record of a sweep: one JSON line per finished run in
//! `results/<name>/runs.jsonl` (or `runs.<i>.jsonl` for shard `i`), each
//! with the run's key, resolved configuration, seed, code version and
//! metrics. Appends are atomic (the file is rewritten to a temporary name
//! and renamed), so a killed sweep leaves every line whole and `--resume`
//! skips the runs already recorded.
//!
//! `metrics` holds only what the same configuration reproduces bit for
//! bit; wall-clock times are kept apart in `timing`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use gpodo_frontends::metrics::{ErrorAgreement, error_agreement};
use gpodo_frontends::rover_measures::RoverMeasures;
use serde::{Deserialize, Serialize};

use crate::config::ExperimentConfig;
use crate::execute::results::ExperimentResults;
use crate::plan::RunSpec;
use crate::util::output::write_atomically;

/// Table I figures of one regressor in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegressorMetrics {
    /// The regressor's label.
    pub label: String,
    /// Pooled RMSE on the test rows.
    pub rmse: f64,
    /// Pooled MAE.
    pub mae: f64,
    /// Negative log predictive density.
    pub nlpd: f64,
    /// Coverage of the 95 % interval.
    pub coverage95: f64,
    /// RMSE per output.
    pub rmse_per_output: Vec<f64>,
    /// The fit's objective (LML or bound), if any.
    pub objective: Option<f64>,
    /// Objective evaluations of the fit, if any.
    pub evaluations: Option<usize>,
}

/// Table II figures of one scheme on one test run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SchemeMetrics {
    /// The scheme's label.
    pub label: String,
    /// The test run.
    pub traverse: String,
    /// Frames processed.
    pub frames: usize,
    /// Keyframes.
    pub keyframes: usize,
    /// Position RMSE (m).
    pub rmse_m: f64,
    /// Largest position error (m).
    pub max_error_m: f64,
    /// Final position error (m).
    pub final_error_m: f64,
    /// Final error over distance travelled (%).
    pub travel_distance_error_percent: f64,
    /// Compute proxy (s).
    pub compute_s: f64,
    /// Tracking losses.
    pub tracking_losses: usize,
    /// Time lost (s).
    pub lost_secs: f64,
    /// Loop closures.
    pub loop_closures: usize,
    /// Loop closures and relocalisations the back end dropped as
    /// inconsistent with the rest of the graph.
    #[serde(default)]
    pub rejected_closures: usize,
    /// Targets learned online.
    pub online_targets: usize,
    /// Drift since the last look, relative pose error, compute per metre
    /// and the RMSE's decomposition.
    #[serde(default)]
    pub rover: RoverMeasures,
}

/// Everything a run measured.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunMetrics {
    /// One entry per regressor, in config order.
    pub regressors: Vec<RegressorMetrics>,
    /// One entry per scheme and test run.
    pub schemes: Vec<SchemeMetrics>,
    /// How alike the two schemes of each A/A pair (a fixed rate and the
    /// same rate at a phase, [`ExperimentConfig::phase_pairs`]) err, per
    /// test run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shared_errors: Vec<SharedError>,
}

/// The error agreement of one A/A pair on one test run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SharedError {
    /// The fixed rate's label.
    pub unshifted: String,
    /// The same rate at a phase.
    pub shifted: String,
    /// The test run.
    pub traverse: String,
    /// How alike their position errors are.
    pub agreement: ErrorAgreement,
}

/// The agreement of every A/A pair of `results` on every test run.
fn shared_errors(results: &ExperimentResults) -> Vec<SharedError> {
    let mut out = Vec::new();
    for (unshifted, shifted) in results.config.phase_pairs() {
        let (a, b) = (
            &results.config.schemes[unshifted].label,
            &results.config.schemes[shifted].label,
        );
        for traverse in results.traverses.iter() {
            let run = |label: &str| {
                results
                    .schemes
                    .iter()
                    .find(|s| s.label == label && s.traverse == traverse.name())
            };
            let (Some(x), Some(y)) = (run(a), run(b)) else {
                continue;
            };
            out.push(SharedError {
                unshifted: a.clone(),
                shifted: b.clone(),
                traverse: traverse.name().to_string(),
                agreement: error_agreement(
                    &x.run.trajectory,
                    &y.run.trajectory,
                    traverse.ground_truth(),
                ),
            });
        }
    }
    out
}

/// Wall-clock times of a run (not reproducible; kept apart).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunTiming {
    /// Fit time per regressor (s).
    pub fit_secs: Vec<f64>,
    /// Scheme run time (s).
    pub scheme_secs: Vec<f64>,
}

/// One line of `runs.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// The run's key.
    pub key: String,
    /// Its position in the plan.
    pub index: usize,
    /// The swept values by dimension.
    pub assignment: BTreeMap<String, String>,
    /// The replicate seed, if the sweep has `seeds:`.
    pub replicate: Option<u64>,
    /// The derived seed the run used, if any.
    pub seed: Option<u64>,
    /// `git describe` of the code.
    pub code_version: String,
    /// The resolved configuration.
    pub config: ExperimentConfig,
    /// What it measured.
    pub metrics: RunMetrics,
    /// How long it took.
    pub timing: RunTiming,
    /// Why the run failed (its metrics are then empty); `gpodo run
    /// --resume` runs it again, and a later successful record of the same
    /// key supersedes this one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl RunRecord {
    /// The record of `run` from its results.
    pub fn new(run: &RunSpec, results: &ExperimentResults) -> Self {
        let regressors = results
            .regressors
            .iter()
            .map(|r| RegressorMetrics {
                label: r.label.clone(),
                rmse: r.evaluation.pooled.rmse,
                mae: r.evaluation.pooled.mae,
                nlpd: r.evaluation.pooled.nlpd,
                coverage95: r.evaluation.pooled.coverage95,
                rmse_per_output: r.evaluation.per_output.iter().map(|p| p.rmse).collect(),
                objective: r.fit.objective,
                evaluations: r.fit.evaluations,
            })
            .collect();
        let schemes = results
            .schemes
            .iter()
            .map(|s| SchemeMetrics {
                label: s.label.clone(),
                traverse: s.traverse.clone(),
                frames: s.run.frames,
                keyframes: s.run.keyframes,
                rmse_m: s.run.metrics.rmse_m,
                max_error_m: s.run.metrics.max_error_m,
                final_error_m: s.run.metrics.final_error_m,
                travel_distance_error_percent: s.run.metrics.travel_distance_error_percent,
                compute_s: s.run.compute_ms / 1e3,
                tracking_losses: s.run.tracking_losses,
                lost_secs: s.run.lost_secs,
                loop_closures: s.run.loop_closures,
                rejected_closures: s.run.rejected_closures,
                online_targets: s.run.online_targets,
                rover: s.run.rover,
            })
            .collect();
        Self {
            key: run.key.clone(),
            index: run.index,
            assignment: run.assignment.clone(),
            replicate: run.replicate,
            seed: run.seed,
            code_version: results.code_version.clone(),
            config: run.config.clone(),
            metrics: RunMetrics {
                regressors,
                schemes,
                shared_errors: shared_errors(results),
            },
            timing: RunTiming {
                fit_secs: results
                    .regressors
                    .iter()
                    .map(|r| r.fit.duration_secs)
                    .collect(),
                scheme_secs: results.schemes.iter().map(|s| s.duration_secs).collect(),
            },
            failure: None,
        }
    }

    /// The record of `run` that failed with `reason`.
    pub fn failed(run: &RunSpec, code_version: &str, reason: String) -> Self {
        Self {
            key: run.key.clone(),
            index: run.index,
            assignment: run.assignment.clone(),
            replicate: run.replicate,
            seed: run.seed,
            code_version: code_version.to_string(),
            config: run.config.clone(),
            metrics: RunMetrics::default(),
            timing: RunTiming::default(),
            failure: Some(reason),
        }
    }
}

/// The record file of a shard (`None`: the whole sweep).
pub fn record_path(dir: &Path, shard: Option<usize>) -> PathBuf {
    match shard {
        Some(i) => dir.join(format!("runs.{i}.jsonl")),
        None => dir.join("runs.jsonl"),
    }
}

/// Every record file in `dir`: `runs.jsonl` and `runs.<i>.jsonl`, sorted.
pub fn record_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    if !dir.is_dir() {
        return Ok(files);
    }
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let shard = name
            .strip_prefix("runs.")
            .and_then(|r| r.strip_suffix(".jsonl"))
            .is_some_and(|mid| mid.chars().all(|c| c.is_ascii_digit()));
        if name == "runs.jsonl" || shard {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// A problem with a record file.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A line is not a record.
    #[error("{}:{line}: not a run record: {detail}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The parser's message.
        detail: String,
    },
}

/// Reads the records of one file (missing file: none).
///
/// # Errors
/// [`RecordError`] naming the file and line.
pub fn read_records(path: &Path) -> Result<Vec<RunRecord>, RecordError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(source) => {
            return Err(RecordError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| RecordError::Malformed {
                path: path.to_path_buf(),
                line: i + 1,
                detail: e.to_string(),
            })
        })
        .collect()
}

/// Appends records to a file, one whole line at a time, atomically.
pub struct RecordWriter {
    path: PathBuf,
    contents: Mutex<String>,
}

impl RecordWriter {
    /// Opens `path`, keeping what it holds (`keep`) or starting empty.
    ///
    /// # Errors
    /// [`RecordError::Io`] when the existing file cannot be read.
    pub fn open(path: &Path, keep: bool) -> Result<Self, RecordError> {
        let contents = if keep {
            match std::fs::read_to_string(path) {
                Ok(t) => t,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
                Err(source) => {
                    return Err(RecordError::Io {
                        path: path.to_path_buf(),
                        source,
                    });
                }
            }
        } else {
            String::new()
        };
        Ok(Self {
            path: path.to_path_buf(),
            contents: Mutex::new(contents),
        })
    }

    /// Appends one record as one line (the whole file is rewritten under a
    /// temporary name, then renamed over the old one).
    ///
    /// # Errors
    /// [`RecordError::Io`].
    pub fn append(&self, record: &RunRecord) -> Result<(), RecordError> {
        let line = serde_json::to_string(record).map_err(|e| RecordError::Io {
            path: self.path.clone(),
            source: std::io::Error::other(e),
        })?;
        let mut contents = self
            .contents
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if !contents.is_empty() && !contents.ends_with('\n') {
            contents.push('\n');
        }
        contents.push_str(&line);
        contents.push('\n');
        write_atomically(&self.path, contents.as_bytes()).map_err(|source| RecordError::Io {
            path: self.path.clone(),
            source,
        })
    }
}
