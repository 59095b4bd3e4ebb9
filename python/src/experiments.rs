//! Experiment files run from Python (`gpodo.run`): the same plan and runner
//! as `gpodo run`, with every run's metrics (what `metrics.json` holds) and
//! each scheme's trajectory handed back instead of, or as well as, written.
//!
//! The runner works on a thread of its own, on a rayon pool of the asked
//! size, with the GIL released. The calling thread waits for its progress
//! events, calls the Python progress callback with each, and checks for
//! Ctrl-C, which stops the runner as the command line's first Ctrl-C does.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::mpsc;
use std::time::Duration;

use gpodo_experiments::error::ConfigError;
use gpodo_experiments::execute::results::ExperimentResults;
use gpodo_experiments::plan::{RunSpec, SweepPlan, load_plan_with};
use gpodo_experiments::report::sweep::write_sweep_report;
use gpodo_experiments::runner::{RunOptions, RunnerError, run_in_memory, run_sweep_observed};
use numpy::PyArray2;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

/// One scheme's trajectory on one test run: times, and the estimated and
/// true poses as `x y z qx qy qz qw` rows.
struct Trajectory {
    scheme: String,
    traverse: String,
    times: Vec<f64>,
    estimate: Vec<[f64; 7]>,
    truth: Vec<[f64; 7]>,
}

/// What Python receives of one run.
struct RunData {
    key: String,
    assignment: BTreeMap<String, String>,
    seed: Option<u64>,
    replicate: Option<u64>,
    /// `metrics.json`'s text, or why the run failed.
    metrics: Result<String, String>,
    trajectories: Vec<Trajectory>,
}

fn pose_row(p: &nalgebra::Isometry3<f64>) -> [f64; 7] {
    let (t, q) = (p.translation.vector, p.rotation.coords);
    [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
}

impl RunData {
    fn new(run: &RunSpec, results: Result<&ExperimentResults, String>) -> Self {
        let (metrics, trajectories) = match results {
            Ok(r) => (
                serde_json::to_string(r).map_err(|e| e.to_string()),
                trajectories(r),
            ),
            Err(reason) => (Err(reason), Vec::new()),
        };
        Self {
            key: run.key.clone(),
            assignment: run.assignment.clone(),
            seed: run.seed,
            replicate: run.replicate,
            metrics,
            trajectories,
        }
    }
}

/// Every scheme's trajectory on every test run of `results`.
fn trajectories(results: &ExperimentResults) -> Vec<Trajectory> {
    results
        .schemes
        .iter()
        .filter_map(|scheme| {
            let traverse = results
                .traverses
                .iter()
                .find(|t| t.name() == scheme.traverse)?;
            let n = traverse.times_secs().len().min(scheme.run.trajectory.len());
            Some(Trajectory {
                scheme: scheme.label.clone(),
                traverse: scheme.traverse.clone(),
                times: traverse.times_secs()[..n].to_vec(),
                estimate: scheme.run.trajectory[..n].iter().map(pose_row).collect(),
                truth: traverse.ground_truth()[..n].iter().map(pose_row).collect(),
            })
        })
        .collect()
}

/// A plan's error as Python sees it: in a dict (whose pseudo-file is
/// `dict`), the key's path first (`schemes[3].selector.fps: …`); in a file
/// (a dict's `base:` included), the command line's message (file, line and
/// column).
fn config_error(e: &ConfigError, dict: Option<&Path>) -> PyErr {
    match e {
        ConfigError::Located {
            file,
            path,
            problem,
            expected,
            ..
        } if Some(file.as_path()) == dict => PyValueError::new_err(format!(
            "{}: {problem}; expected {expected}",
            if path.is_empty() {
                "the experiment"
            } else {
                path
            }
        )),
        e => PyValueError::new_err(e.to_string()),
    }
}

/// What the runner thread hands back.
type RunnerOutput = Result<(Vec<RunData>, Option<PathBuf>), RunnerError>;

/// Runs `plan` on a pool of `threads` (the machine's cores when None),
/// writing to `out` when given; sends `(done, total, key)` after each run.
fn run_plan(
    plan: &SweepPlan,
    out: Option<PathBuf>,
    force: bool,
    threads: Option<usize>,
    events: &mpsc::Sender<(usize, usize, String)>,
) -> Result<RunnerOutput, rayon::ThreadPoolBuildError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()?;
    let total = plan.runs.len();
    let collected = Mutex::new(Vec::<(usize, RunData)>::new());
    let events = Mutex::new(events.clone());
    // Sent under the lock, so that the counts arrive in order.
    let observer = |run: &RunSpec, results: &ExperimentResults| {
        let data = RunData::new(run, Ok(results));
        let mut c = collected
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        c.push((run.index, data));
        if let Ok(tx) = events.lock() {
            let _ = tx.send((c.len(), total, run.key.clone()));
        }
    };
    Ok(pool.install(|| -> RunnerOutput {
        let report = match out {
            None => {
                let failed = run_in_memory(plan, &observer)?;
                let mut c = collected
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                for (index, reason) in failed {
                    c.push((index, RunData::new(&plan.runs[index], Err(reason))));
                }
                None
            }
            Some(dir) => {
                let single = plan.runs.len() == 1;
                let options = RunOptions {
                    out: Some(dir),
                    force: force || single,
                    quiet: true,
                    ..RunOptions::default()
                };
                let outcome = run_sweep_observed(plan, &options, &observer)?;
                let mut c = collected
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                for (key, reason) in outcome.failed {
                    if let Some(run) = plan.runs.iter().find(|r| r.key == key) {
                        c.push((run.index, RunData::new(run, Err(reason))));
                    }
                }
                // What `gpodo run` writes after the runs: a single run's
                // summary beside its report, a sweep's report.
                let written = if single {
                    write_sweep_report(&outcome.dir, "summary.md")
                        .map_err(|e| RunnerError::Report(e.into()))?;
                    Some(outcome.dir.join("report.md"))
                } else {
                    let report = write_sweep_report(&outcome.dir, "report.md")
                        .map_err(|e| RunnerError::Report(e.into()))?;
                    Some(report.markdown)
                };
                written.filter(|path| path.exists())
            }
        };
        let mut runs = std::mem::take(
            &mut *collected
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
        );
        runs.sort_by_key(|(i, _)| *i);
        Ok((runs.into_iter().map(|(_, d)| d).collect(), report))
    }))
}

/// One run as Python receives it: `(key, assignment, seed, replicate,
/// metrics JSON or None, failure or None, trajectories)`, each trajectory
/// `(scheme, traverse, times n × 1, estimate n × 7, truth n × 7)`.
type PyRun<'py> = (
    String,
    BTreeMap<String, String>,
    Option<u64>,
    Option<u64>,
    Option<String>,
    Option<String>,
    Vec<PyTrajectory<'py>>,
);

/// `(scheme, traverse, times, estimate, truth)`.
type PyTrajectory<'py> = (
    String,
    String,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

fn rows_array<'py, const N: usize>(
    py: Python<'py>,
    rows: &[[f64; N]],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    numpy::ndarray::Array2::from_shape_vec((rows.len(), N), flat)
        .map(|a| numpy::IntoPyArray::into_pyarray(a, py))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// Runs the experiment file `file` (or `text`, a YAML or JSON experiment
/// read as if it were `file`) through `gpodo run`'s runner. Returns the
/// experiment's name, the report's path (None when `out` is None: nothing
/// is written) and its runs in plan order. `force` starts a sweep's folder
/// over. `progress(done, total, key)` is called on this thread after each
/// run.
#[pyfunction]
#[pyo3(signature = (file, text=None, out=None, seeds=None, threads=None, progress=None, force=false))]
#[allow(clippy::type_complexity)]
// Python's keyword arguments, one parameter each.
#[allow(clippy::too_many_arguments)]
pub fn run_experiment<'py>(
    py: Python<'py>,
    file: PathBuf,
    text: Option<String>,
    out: Option<PathBuf>,
    seeds: Option<Vec<u64>>,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
    force: bool,
) -> PyResult<(String, Option<String>, Vec<PyRun<'py>>)> {
    let from_dict = text.is_some();
    let plan = py
        .detach(|| load_plan_with(Path::new(&file), text.as_deref(), seeds.as_deref()))
        .map_err(|e| config_error(&e, from_dict.then_some(file.as_path())))?;
    let name = plan.name.clone();
    gpodo_experiments::util::stop::clear();
    let (tx, rx) = mpsc::channel();
    let rx = Mutex::new(rx);
    let next = || match rx.lock() {
        Ok(rx) => rx.recv_timeout(Duration::from_millis(100)),
        Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
    };
    let worker = std::thread::spawn(move || run_plan(&plan, out, force, threads, &tx));
    let mut interrupted = None;
    loop {
        match py.detach(next) {
            Ok((done, total, key)) => {
                if let Some(callback) = &progress
                    && interrupted.is_none()
                    && let Err(e) = callback.call1((done, total, key))
                {
                    gpodo_experiments::util::stop::request();
                    interrupted = Some(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        }
        if interrupted.is_none()
            && let Err(e) = py.check_signals()
        {
            gpodo_experiments::util::stop::request();
            interrupted = Some(e);
        }
    }
    let outcome = py.detach(|| worker.join());
    gpodo_experiments::util::stop::clear();
    if let Some(e) = interrupted {
        return Err(e);
    }
    let outcome = outcome.map_err(|panic| crate::panic_error(panic.as_ref()))?;
    let (runs, report) = outcome
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
        .map_err(|e| match e {
            RunnerError::Pipeline(e) => PyValueError::new_err(e.to_string()),
            RunnerError::ResultsExist { path } => PyValueError::new_err(format!(
                "{} already holds the sweep's runs; pass force=True to start it over, or another `out`",
                path.display()
            )),
            e => PyRuntimeError::new_err(e.to_string()),
        })?;
    let runs = runs
        .into_iter()
        .map(|r| -> PyResult<PyRun<'py>> {
            let trajectories = r
                .trajectories
                .into_iter()
                .map(|t| -> PyResult<PyTrajectory<'py>> {
                    let times: Vec<[f64; 1]> = t.times.iter().map(|&s| [s]).collect();
                    Ok((
                        t.scheme,
                        t.traverse,
                        rows_array(py, &times)?,
                        rows_array(py, &t.estimate)?,
                        rows_array(py, &t.truth)?,
                    ))
                })
                .collect::<PyResult<_>>()?;
            let (metrics, failure) = match r.metrics {
                Ok(m) => (Some(m), None),
                Err(f) => (None, Some(f)),
            };
            Ok((
                r.key,
                r.assignment,
                r.seed,
                r.replicate,
                metrics,
                failure,
                trajectories,
            ))
        })
        .collect::<PyResult<_>>()?;
    Ok((name, report.map(|p| p.display().to_string()), runs))
}
