//! `kind: external` against real Python plugins: the NumPy ridge example
//! (fit, predict and online update, checked against the closed form
//! computed here with nalgebra) and a plugin that fails on purpose in every
//! way the protocol guards against. Needs a `python3` with NumPy
//! (`GPODO_PYTHON` names another interpreter); without one the tests say
//! so and pass, unless `GPODO_REQUIRE_PYTHON` is set (as CI sets it).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use gpodo_regressors::{ExternalParams, ExternalRegressor, RegressorSpec};
use gpodo_traits::{ResidualDataset, ResidualRegressor, SampleMatrix};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The interpreter, or `None` (after saying why) when there is no Python
/// with NumPy and CI did not ask for one.
fn python() -> Option<String> {
    gpodo_testkit::python_with(&["numpy"], "NumPy")
}

fn plugin(python: &str, script: &Path, args: &[&str], timeout_secs: f64) -> ExternalRegressor {
    let mut command = vec![python.to_string(), script.to_string_lossy().into_owned()];
    command.extend(args.iter().map(|a| a.to_string()));
    let mut params = ExternalParams::new(command);
    params.timeout_secs = timeout_secs;
    ExternalRegressor::new(params).unwrap()
}

fn ridge(python: &str, alpha: f64) -> ExternalRegressor {
    let script = root().join("plugins/python/examples/ridge.py");
    let mut params =
        ExternalParams::new(vec![python.into(), script.to_string_lossy().into_owned()]);
    params.options.insert("alpha".into(), alpha.into());
    ExternalRegressor::new(params).unwrap()
}

fn misbehaving(python: &str, mode: &str, timeout_secs: f64) -> ExternalRegressor {
    plugin(
        python,
        &root().join("regressors/tests/plugins/misbehaving.py"),
        &[mode],
        timeout_secs,
    )
}

fn data(n: usize, seed: u64) -> ResidualDataset {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let d = 4;
    let x: Vec<Vec<f64>> = (0..n)
        .map(|_| (0..d).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect();
    let y: Vec<Vec<f64>> = x
        .iter()
        .map(|r| {
            vec![
                0.5 * r[0] - r[1] + 0.1 + rng.random_range(-0.05..0.05),
                r[2] * r[3] + rng.random_range(-0.05..0.05),
                -0.2 + rng.random_range(-0.05..0.05),
            ]
        })
        .collect();
    ResidualDataset::new(
        SampleMatrix::from_rows(d, &x).unwrap(),
        SampleMatrix::from_rows(3, &y).unwrap(),
        (0..d).map(|i| format!("x{i}")).collect(),
        vec!["vx".into(), "vy".into(), "vz".into()],
    )
    .unwrap()
}

/// Bayesian ridge in closed form: `P = αI + ΦᵀΦ`, `w = P⁻¹Φᵀy`, noise the
/// mean squared residual, variance `noise (1 + φᵀP⁻¹φ)`.
fn closed_form(
    train: &ResidualDataset,
    alpha: f64,
    x: &SampleMatrix,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let design = |m: &SampleMatrix| {
        DMatrix::from_fn(m.nrows(), m.ncols() + 1, |i, j| {
            if j < m.ncols() { m.get(i, j) } else { 1.0 }
        })
    };
    let phi = design(&train.inputs);
    let y = DMatrix::from_fn(train.len(), 3, |i, j| train.targets.get(i, j));
    let p = DMatrix::identity(phi.ncols(), phi.ncols()) * alpha + phi.transpose() * &phi;
    let p_inv = p.clone().try_inverse().unwrap();
    let w = &p_inv * phi.transpose() * &y;
    let residual = &y - &phi * &w;
    let noise: Vec<f64> = (0..3)
        .map(|j| residual.column(j).norm_squared() / train.len() as f64 + 1e-12)
        .collect();
    let q = design(x);
    let mean = &q * &w;
    let var = DMatrix::from_fn(x.nrows(), 3, |i, j| {
        let row: DVector<f64> = q.row(i).transpose();
        noise[j] * (1.0 + (row.transpose() * &p_inv * &row)[(0, 0)])
    });
    (mean, var)
}

fn process_is_gone(pid: u32) -> bool {
    // Reaped processes leave no /proc entry (a zombie would).
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        if !Path::new(&format!("/proc/{pid}")).exists() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

#[test]
fn the_ridge_plugin_fits_and_predicts_the_closed_form() {
    let Some(python) = python() else { return };
    let train = data(200, 1);
    let test = data(30, 2);
    let mut model = ridge(&python, 2.5);
    assert!(model.supports_online_update());
    let report = model.fit(&train).unwrap();
    assert_eq!(report.n_samples, 200);
    assert_eq!(report.parameters[0], ("alpha".to_string(), 2.5));
    let p = model.predict(&test.inputs).unwrap();
    let (mean, var) = closed_form(&train, 2.5, &test.inputs);
    for i in 0..30 {
        for j in 0..3 {
            assert!(
                (p.mean.get(i, j) - mean[(i, j)]).abs() < 1e-10,
                "mean {i},{j}"
            );
            assert!((p.variance.get(i, j) - var[(i, j)]).abs() < 1e-10 * var[(i, j)].max(1.0));
        }
    }
    let pid = model.process_id().unwrap();
    drop(model);
    assert!(
        process_is_gone(pid),
        "the plugin {pid} outlived its regressor"
    );
}

#[test]
fn online_updates_through_the_plugin_equal_a_batch_fit() {
    let Some(python) = python() else { return };
    let all = data(120, 3);
    let test = data(10, 4);
    let mut online = ridge(&python, 1.0);
    online
        .fit(&all.select(&(0..60).collect::<Vec<_>>()))
        .unwrap();
    for i in 60..120 {
        online
            .update(all.inputs.row(i), all.targets.row(i))
            .unwrap();
    }
    let (mean, var) = closed_form(&all, 1.0, &test.inputs);
    let p = online.predict(&test.inputs).unwrap();
    for i in 0..10 {
        for j in 0..3 {
            assert!((p.mean.get(i, j) - mean[(i, j)]).abs() < 1e-9);
            assert!((p.variance.get(i, j) - var[(i, j)]).abs() < 1e-9);
        }
    }
    // From nothing, as the online schemes use it.
    let mut fresh = ridge(&python, 1.0);
    for i in 0..120 {
        fresh.update(all.inputs.row(i), all.targets.row(i)).unwrap();
    }
    let q = fresh.predict(&test.inputs).unwrap();
    for (a, b) in q.mean.as_slice().iter().zip(p.mean.as_slice()) {
        assert!((a - b).abs() < 1e-9);
    }
}

#[test]
fn the_spec_resolves_the_script_against_the_experiment_folder() {
    let yaml = "kind: external\ncommand: [python3, examples/ridge.py]\nalpha: 0.5\nlabel: ridge\n";
    let spec: RegressorSpec = serde_saphyr::from_str(yaml).unwrap();
    let RegressorSpec::External(params) = spec.clone() else {
        panic!("{spec:?}")
    };
    assert_eq!(params.options.get("alpha"), Some(&serde_json::json!(0.5)));
    assert!(!params.options.contains_key("kind"));
    let resolved = params.resolved_against(&root().join("plugins/python"));
    assert_eq!(resolved.command[0], "python3");
    assert!(Path::new(&resolved.command[1]).is_absolute());
    assert!(Path::new(&resolved.command[1]).exists());
    assert_eq!(spec.label(), "ridge [alpha=0.5]");
    let slow: RegressorSpec = serde_saphyr::from_str(&format!("{yaml}timeout_secs: 5\n")).unwrap();
    assert_eq!(
        slow.label(),
        "ridge [alpha=0.5]",
        "the timeout is not a model setting"
    );
    let bad: Result<RegressorSpec, _> = serde_saphyr::from_str("kind: external\ncommand: []\n");
    let e = bad.unwrap().validate().unwrap_err().to_string();
    assert!(e.contains("command"), "{e}");
}

/// Fits (and predicts with) a misbehaving plugin and returns the error
/// and the plugin's pid.
fn failure(python: &str, mode: &str, timeout_secs: f64) -> (String, u32) {
    let mut model = misbehaving(python, mode, timeout_secs);
    let train = data(20, 5);
    let started = model.supports_online_update();
    let pid = model.process_id().unwrap();
    let error = match model.fit(&train) {
        Err(e) => e.to_string(),
        Ok(_) => match model.predict(&train.inputs) {
            Err(e) => e.to_string(),
            Ok(_) => match model.update(train.inputs.row(0), train.targets.row(0)) {
                Err(e) => e.to_string(),
                Ok(()) => panic!("mode {mode} did not fail (update capability {started})"),
            },
        },
    };
    drop(model);
    (error, pid)
}

#[test]
fn every_failure_names_the_regressor_the_request_and_the_stderr_and_reaps_the_plugin() {
    let Some(python) = python() else { return };
    let cases: [(&str, &str, &[&str]); 6] = [
        (
            "crash_on_fit",
            "`fit`",
            &["exited", "about to crash on purpose"],
        ),
        (
            "garbage_on_fit",
            "`fit`",
            &["not the protocol's JSON", "this is not json"],
        ),
        (
            "wrong_shape",
            "`predict`",
            &["`mean` is 19 × 3, expected 20 × 3"],
        ),
        (
            "nan_variance",
            "`predict`",
            &["`variance` row 10, output 1 is NaN"],
        ),
        (
            "refuse_fit",
            "`fit`",
            &["cannot fit: refused on purpose", "Traceback"],
        ),
        ("no_update", "", &["does not support online updates"]),
    ];
    for (mode, request, needles) in cases {
        let (error, pid) = failure(&python, mode, 30.0);
        if !request.is_empty() {
            assert!(
                error.contains(&format!(
                    "external regressor `external: misbehaving.py`, request {request}"
                )),
                "{mode}: {error}"
            );
        }
        for needle in needles {
            assert!(
                error.contains(needle),
                "{mode}: `{needle}` missing from: {error}"
            );
        }
        assert!(process_is_gone(pid), "{mode}: plugin {pid} left behind");
    }
}

#[test]
fn a_plugin_that_hangs_is_killed_after_its_timeout() {
    let Some(python) = python() else { return };
    let start = Instant::now();
    let (error, pid) = failure(&python, "hang_on_predict", 1.5);
    assert!(
        start.elapsed() < Duration::from_secs(20),
        "{:?}",
        start.elapsed()
    );
    assert!(error.contains("no reply within 1.5 s"), "{error}");
    assert!(error.contains("hanging on purpose"), "{error}");
    assert!(process_is_gone(pid));
}

#[test]
fn a_plugin_of_another_protocol_version_is_refused() {
    let Some(python) = python() else { return };
    let mut model = misbehaving(&python, "old_protocol", 30.0);
    let e = model.fit(&data(5, 6)).unwrap_err().to_string();
    assert!(
        e.contains("request `hello`") && e.contains("protocol 0"),
        "{e}"
    );
}

#[test]
fn a_missing_program_is_an_error_naming_it() {
    let mut model = ExternalRegressor::new(ExternalParams::new(vec![
        "/nonexistent/gpodo-plugin".into(),
    ]))
    .unwrap();
    let e = model.fit(&data(5, 7)).unwrap_err().to_string();
    assert!(
        e.contains("/nonexistent/gpodo-plugin") && e.contains("could not start"),
        "{e}"
    );
}
