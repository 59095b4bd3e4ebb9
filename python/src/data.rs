//! Rover logs for Python: a simulated testbed (`gpodo.simulate`), a bag
//! imported through a topic map (`gpodo.read_bag`), and the residual rows
//! of logs (`gpodo.residuals`), each as the command line computes them.
//! A log crosses as its CSV's columns and rows (`<name>.csv`).

use std::path::PathBuf;

use gpodo_datasets::bags::import::import_bag;
use gpodo_datasets::log::{RoverLog, log_table, read_log_csv};
use gpodo_datasets::residuals::ResidualConfig;
use gpodo_experiments::commands::import::{read_topic_map, unit_check};
use gpodo_experiments::commands::simulate::{SimulateFormat, SimulateOptions, simulate_logs};
use gpodo_experiments::config::MotionModelSpec;
use gpodo_experiments::execute::data::residual_rows;
use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::{array, detached, value_error};

/// A log as Python receives it: `(name, columns, rows n × columns, camera
/// frame times)`.
type PyLog<'py> = (String, Vec<String>, Bound<'py, PyArray2<f64>>, Vec<f64>);

fn py_log<'py>(py: Python<'py>, log: &RoverLog) -> PyResult<PyLog<'py>> {
    let (columns, rows) = log_table(log);
    let width = columns.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    let table = gpodo_traits::SampleMatrix::from_row_major(flat.len() / width.max(1), width, flat)
        .map_err(value_error)?;
    Ok((
        log.name.clone(),
        columns,
        array(py, &table)?,
        log.camera_times_secs.clone(),
    ))
}

/// The training and test runs of a simulated testbed, as `gpodo simulate
/// --format csv` writes them.
#[pyfunction]
#[pyo3(signature = (preset, seed, training_runs=None, training_run_secs=None, test_max_secs=None, imu=true))]
#[allow(clippy::type_complexity)]
pub fn simulate<'py>(
    py: Python<'py>,
    preset: &str,
    seed: u64,
    training_runs: Option<usize>,
    training_run_secs: Option<f64>,
    test_max_secs: Option<f64>,
    imu: bool,
) -> PyResult<(Vec<PyLog<'py>>, Vec<PyLog<'py>>)> {
    let preset = serde_json::from_value(serde_json::Value::String(preset.into()))
        .map_err(|_| PyValueError::new_err(format!("preset `{preset}`: expected exoter-prl")))?;
    let options = SimulateOptions {
        preset,
        seed,
        training_runs,
        training_run_secs,
        test_max_secs,
        format: SimulateFormat::Csv,
        units: Default::default(),
        imu,
        camera: None,
    };
    let (train, test) = detached(py, || simulate_logs(&options))?.map_err(value_error)?;
    let convert = |logs: &[RoverLog]| logs.iter().map(|l| py_log(py, l)).collect::<PyResult<_>>();
    Ok((convert(&train)?, convert(&test)?))
}

/// The bag at `path` imported through the topic map at `topics`, as
/// `gpodo import` does, with the warnings it prints: the unit check
/// against `rover` (a robot description) and any damage found.
#[pyfunction]
#[pyo3(signature = (path, topics, name, rover=None))]
pub fn read_bag<'py>(
    py: Python<'py>,
    path: PathBuf,
    topics: PathBuf,
    name: String,
    rover: Option<PathBuf>,
) -> PyResult<(PyLog<'py>, Vec<String>)> {
    let map = detached(py, || read_topic_map(&topics))?.map_err(value_error)?;
    let (log, report) = detached(py, || import_bag(&path, &name, &map))?
        .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
    let mut warnings = Vec::new();
    if !report.damage.is_empty() {
        warnings.push(format!("{}: {}", path.display(), report.damage));
    }
    if let Some(rover) = rover {
        let logs = [log.clone()];
        match detached(py, || unit_check(&logs, &rover))?.map_err(value_error)? {
            None => warnings.push(format!(
                "no unit check: fewer than {} seconds drive faster than {} m/s",
                gpodo_datasets::speed_check::MIN_MOVING_WINDOWS,
                gpodo_datasets::speed_check::MOVING_SPEED_MPS
            )),
            Some(ratio) => {
                if let Some(warning) = gpodo_datasets::speed_check::unit_warning(ratio) {
                    warnings.push(warning.to_string());
                }
            }
        }
    }
    Ok((py_log(py, &log)?, warnings))
}

/// The residual rows of the logs at `paths` (rover-log CSVs, in order)
/// under the motion model `motion_model` and the residual settings
/// `residuals` (the JSON of an experiment's `motion_model:` and
/// `residuals:`): `(inputs, targets, input names, target names)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn residuals<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    motion_model: &str,
    residuals: &str,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
    Vec<String>,
)> {
    let spec: MotionModelSpec = serde_json::from_str(motion_model)
        .map_err(|e| PyValueError::new_err(format!("motion_model: {e}")))?;
    let config: ResidualConfig = serde_json::from_str(residuals)
        .map_err(|e| PyValueError::new_err(format!("residuals: {e}")))?;
    let rows = detached(py, || -> Result<_, String> {
        let logs = paths
            .iter()
            .map(|p| read_log_csv(p).map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()?;
        residual_rows(&spec, &config, &logs).map_err(|e| e.to_string())
    })?
    .map_err(PyValueError::new_err)?;
    Ok((
        array(py, &rows.inputs)?,
        array(py, &rows.targets)?,
        rows.input_names,
        rows.target_names,
    ))
}
