//! The native half of the `gpodo` Python package (`gpodo._native`): a fit
//! of any saved-model regressor kind (exact GP, sparse GP, ILGR) from a
//! settings object, prediction with the noisy and the latent variance, online
//! updates, and the saved-model file the CLI reads and writes. It has no
//! numerics of its own: everything goes through `gpodo-regressors`' model
//! file. The scikit-learn estimators are the Python half (`gpodo/`).
//!
//! The GIL is released during fits and predictions. A fit reports each
//! optimiser iteration through a hook that takes the GIL back briefly: it
//! checks for Ctrl-C (raising `KeyboardInterrupt` at the next iteration)
//! and, when asked, prints progress to `sys.stderr`. A Rust panic becomes a
//! `RuntimeError`.

use std::ops::ControlFlow;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use gpodo_regressors::RegressorSpec;
use gpodo_regressors::model_file::{ModelFile, Predictor, Provenance};
use gpodo_traits::{FitProgress, ResidualDataset, SampleMatrix};
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

mod data;
mod experiments;

/// A message for any error: a `ValueError`.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A Rust panic as Python sees it: a `RuntimeError` with its message.
fn panic_error(panic: &(dyn std::any::Any + Send)) -> PyErr {
    let what = panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "unknown".into());
    PyRuntimeError::new_err(format!(
        "gpodo failed inside Rust (a bug; please report it): {what}"
    ))
}

/// Runs `f` with the GIL released; a panic becomes a `RuntimeError`.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    py.detach(|| catch_unwind(AssertUnwindSafe(f)))
        .map_err(|panic| panic_error(panic.as_ref()))
}

/// A NumPy array as a row-major matrix (it may be a strided view).
fn matrix(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<SampleMatrix> {
    let view = a.as_array();
    let (rows, cols) = view.dim();
    let data: Vec<f64> = view.iter().copied().collect();
    SampleMatrix::from_row_major(rows, cols, data).map_err(|e| value_error(format!("{name}: {e}")))
}

/// A row-major matrix as a NumPy array.
fn array<'py>(py: Python<'py>, m: &SampleMatrix) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows: Vec<f64> = m.rows().flat_map(|r| r.iter().copied()).collect();
    numpy::ndarray::Array2::from_shape_vec((m.nrows(), m.ncols()), rows)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The fit's progress hook: Ctrl-C stops the fit at the next iteration,
/// and with `verbose` each iteration is printed to `sys.stderr`.
struct PythonProgress {
    verbose: bool,
    interrupted: Mutex<Option<PyErr>>,
}

impl PythonProgress {
    /// Whether Ctrl-C was pressed, now or before: Python's signal handlers
    /// run here, and a `KeyboardInterrupt` is kept for the fit to raise.
    fn interrupted(&self, py: Python<'_>) -> bool {
        let Ok(mut slot) = self.interrupted.lock() else {
            return true;
        };
        if slot.is_some() {
            return true;
        }
        if let Err(e) = py.check_signals() {
            *slot = Some(e);
            return true;
        }
        false
    }
}

impl FitProgress for PythonProgress {
    fn stop_requested(&self) -> bool {
        Python::attach(|py| self.interrupted(py))
    }

    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> ControlFlow<()> {
        Python::attach(|py| {
            if self.interrupted(py) {
                return ControlFlow::Break(());
            }
            if self.verbose {
                let line = format!(
                    "gpodo: start {start}, iteration {iteration}: objective {objective:.4}\n"
                );
                let _ = py
                    .import("sys")
                    .and_then(|sys| sys.getattr("stderr"))
                    .and_then(|err| err.call_method1("write", (line,)));
            }
            ControlFlow::Continue(())
        })
    }
}

/// Mean, noisy-target variance and latent variance (None for ILGR).
type Moments<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Option<Bound<'py, PyArray2<f64>>>,
);

/// A trained model: its saved-model file and the model rebuilt from it.
#[pyclass(module = "gpodo._native", name = "Model")]
struct Model {
    file: ModelFile,
    predictor: Predictor,
    report: Option<String>,
}

impl Model {
    fn from_file(py: Python<'_>, file: ModelFile, report: Option<String>) -> PyResult<Self> {
        let predictor = detached(py, || file.predictor())?.map_err(value_error)?;
        Ok(Self {
            file,
            predictor,
            report,
        })
    }
}

#[pymethods]
impl Model {
    /// Mean, noisy-target variance and latent variance (None for ILGR) of
    /// each row of `x`, whose columns are `columns` (the model's own
    /// inputs, in its order, when None).
    #[pyo3(signature = (x, columns=None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        columns: Option<Vec<String>>,
    ) -> PyResult<Moments<'py>> {
        let rows = matrix("X", &x)?;
        let columns = columns.unwrap_or_else(|| self.file.input_names.clone());
        if columns.len() != rows.ncols() {
            return Err(value_error(format!(
                "X has {} columns, {} names given",
                rows.ncols(),
                columns.len()
            )));
        }
        let (p, latent) = detached(py, || self.predictor.predict_with_latent(&columns, &rows))?
            .map_err(value_error)?;
        let latent = latent.map(|l| array(py, &l)).transpose()?;
        Ok((array(py, &p.mean)?, array(py, &p.variance)?, latent))
    }

    /// Learns from more rows, one at a time (online learning: ILGR).
    fn update(
        &mut self,
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (rows, targets) = (matrix("X", &x)?, matrix("y", &y)?);
        if rows.nrows() != targets.nrows() {
            return Err(value_error(format!(
                "X has {} rows, y has {}",
                rows.nrows(),
                targets.nrows()
            )));
        }
        let names = self.file.input_names.clone();
        let predictor = &mut self.predictor;
        detached(py, move || -> Result<(), String> {
            let inputs = predictor
                .model_inputs(&names, &rows)
                .map_err(|e| e.to_string())?;
            for (xi, yi) in inputs.rows().zip(targets.rows()) {
                predictor
                    .model_mut()
                    .update(xi, yi)
                    .map_err(|e| e.to_string())?;
            }
            Ok(())
        })?
        .map_err(value_error)?;
        if let Some(state) = self.predictor.saved_state() {
            self.file.state = state;
        }
        Ok(())
    }

    /// Writes the model file (what `gpodo predict --model` reads).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        detached(py, || self.file.save(&path))?.map_err(value_error)
    }

    /// The model file as JSON text (for pickling).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.file).map_err(value_error)
    }

    /// The input column names, in the model's order.
    #[getter]
    fn input_names(&self) -> Vec<String> {
        self.file.input_names.clone()
    }

    /// The output names.
    #[getter]
    fn target_names(&self) -> Vec<String> {
        self.file.target_names.clone()
    }

    /// The regressor's label (`exact GP: rbf`).
    #[getter]
    fn label(&self) -> String {
        self.file.label.clone()
    }

    /// The log marginal likelihood of each output group of an exact GP
    /// (one group unless outputs are independent); None for other kinds.
    fn log_marginal_likelihoods(&self) -> Option<Vec<f64>> {
        self.predictor.log_marginal_likelihoods()
    }

    /// What the fit did, as JSON (None for a loaded model).
    #[getter]
    fn fit_report(&self) -> Option<String> {
        self.report.clone()
    }
}

/// Fits the regressor `spec` (the JSON of a YAML `regressors:` entry) on
/// `x` (n × d) and `y` (n × p), with the GIL released.
#[pyfunction]
#[pyo3(signature = (spec, x, y, input_names, target_names, verbose=false))]
fn fit(
    py: Python<'_>,
    spec: &str,
    x: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    input_names: Vec<String>,
    target_names: Vec<String>,
    verbose: bool,
) -> PyResult<Model> {
    let spec: RegressorSpec = serde_json::from_str(spec).map_err(value_error)?;
    spec.validate().map_err(value_error)?;
    if x.shape()[0] != y.shape()[0] {
        return Err(value_error(format!(
            "X has {} rows, y has {}",
            x.shape()[0],
            y.shape()[0]
        )));
    }
    let data = ResidualDataset::new(
        matrix("X", &x)?,
        matrix("y", &y)?,
        input_names,
        target_names,
    )
    .map_err(value_error)?;
    let progress = Arc::new(PythonProgress {
        verbose,
        interrupted: Mutex::new(None),
    });
    let hook: Arc<dyn FitProgress> = progress.clone();
    let provenance = Provenance {
        experiment: "python".into(),
        code_version: env!("CARGO_PKG_VERSION").into(),
        training_rows: data.len(),
    };
    let fitted = detached(py, || {
        ModelFile::fit_with_progress(&spec, &data, None, provenance, Some(hook))
    })?;
    if let Some(e) = progress.interrupted.lock().ok().and_then(|mut e| e.take()) {
        return Err(e);
    }
    let (file, _, report) = fitted.map_err(value_error)?;
    let report = serde_json::to_string(&report).map_err(value_error)?;
    Model::from_file(py, file, Some(report))
}

/// Reads a model file (what `gpodo fit --save` writes).
#[pyfunction]
fn load_model(py: Python<'_>, path: PathBuf) -> PyResult<Model> {
    let file = detached(py, || ModelFile::load(&path))?.map_err(value_error)?;
    Model::from_file(py, file, None)
}

/// A model from its JSON text ([`Model::to_json`]).
#[pyfunction]
fn model_from_json(py: Python<'_>, text: &str) -> PyResult<Model> {
    let file: ModelFile = serde_json::from_str(text).map_err(value_error)?;
    Model::from_file(py, file, None)
}

/// The kernel names an expression may use.
#[pyfunction]
fn kernel_names() -> Vec<String> {
    gpodo_regressors::kernels::LeafName::ALL
        .iter()
        .map(|n| n.as_str().to_string())
        .collect()
}

/// Panics inside Rust with `message`, through the same boundary as a fit,
/// so that the tests can check a panic reaches Python as a
/// `RuntimeError` (not exported by the `gpodo` package).
#[pyfunction]
fn _panic_for_tests(py: Python<'_>, message: String) -> PyResult<()> {
    detached::<()>(py, move || panic!("{message}"))
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(load_model, m)?)?;
    m.add_function(wrap_pyfunction!(model_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(kernel_names, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::run_experiment, m)?)?;
    m.add_function(wrap_pyfunction!(data::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(data::read_bag, m)?)?;
    m.add_function(wrap_pyfunction!(data::residuals, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    Ok(())
}
