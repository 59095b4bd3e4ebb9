//! Trained models out of an experiment: `gpodo fit --save` then `gpodo
//! predict` (or `ModelFile::load` in library code) gives the in-process
//! model's predictions to 1e-12 from raw input rows matched by column name;
//! bad model files (truncated, another version, not a model) and input rows
//! without the model's columns are refused with errors naming them.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

use gpodo_experiments::config::ExperimentConfig;
use gpodo_experiments::execute::models::{fit_model, read_rows};
use gpodo_regressors::model_file::ModelFile;

mod common;

use common::{GPODO, gpodo_on};

const TINY: &str = "name: tiny-model
dataset: { kind: simulated, preset: exoter-prl, seed: 3, training_runs: 1, training_run_secs: 90, test_max_secs: 60 }
regressors:
  - kind: zero
  - kind: exact_gp
    kernel: rbf
    hyperopt: { max_iters: 30 }
  - kind: sparse_gp
    kernel: rbf
    inducing: { count: 20 }
    hyperopt: { max_iters: 20 }
  - kind: ilgr
  - kind: knn
";

fn write_config(dir: &Path) -> std::path::PathBuf {
    let file = dir.join("tiny.yaml");
    std::fs::write(&file, TINY).unwrap();
    file
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn a_saved_model_predicts_what_the_in_process_model_predicted() {
    let tmp = tempfile::tempdir().unwrap();
    let file = write_config(tmp.path());
    let config = ExperimentConfig::from_path(&file).unwrap();
    for label in [
        "exact GP: rbf [hyperopt.max_iters=30]",
        "ILGR",
        "sparse GP (VFE, m=20): rbf [hyperopt.max_iters=20]",
    ] {
        let fitted = fit_model(&config, label).unwrap();
        let path = tmp.path().join("m.gpodo");
        fitted.file.save(&path).unwrap();
        let loaded = ModelFile::load(&path).unwrap();
        let again = tmp.path().join("again.gpodo");
        loaded.save(&again).unwrap();
        assert!(
            std::fs::read(&path).unwrap() == std::fs::read(&again).unwrap(),
            "{label}: a loaded model saves to the same bytes"
        );
        // Raw rows, columns reversed: matched by name, z-scored by the file.
        let (names, rows) = &fitted.test_inputs;
        let reversed_names: Vec<String> = names.iter().rev().cloned().collect();
        let reversed: Vec<Vec<f64>> = rows
            .rows()
            .map(|r| r.iter().rev().copied().collect())
            .collect();
        let reversed = gpodo_traits::SampleMatrix::from_rows(names.len(), &reversed).unwrap();
        let p = loaded
            .predictor()
            .unwrap()
            .predict(&reversed_names, &reversed)
            .unwrap();
        let q = &fitted.test_predictions;
        assert_eq!(p.mean.nrows(), rows.nrows());
        for (a, b) in p.mean.as_slice().iter().zip(q.mean.as_slice()) {
            assert!(close(*a, *b), "{label}: mean {a} vs {b}");
        }
        for (a, b) in p.variance.as_slice().iter().zip(q.variance.as_slice()) {
            assert!(close(*a, *b), "{label}: variance {a} vs {b}");
        }
    }
}

#[test]
fn gpodo_fit_then_predict_on_the_runs_residual_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let file = write_config(tmp.path());
    let model = tmp.path().join("gp.gpodo");
    let out = Command::new(GPODO)
        .args(["--quiet", "fit"])
        .arg(&file)
        .args([
            "--regressor",
            "exact GP: rbf [hyperopt.max_iters=30]",
            "--save",
        ])
        .arg(&model)
        .output()
        .unwrap();
    common::assert_succeeded(&out, "");
    assert!(String::from_utf8_lossy(&out.stdout).contains("held-out RMSE"));
    // The rows `gpodo run` writes (raw inputs and the residual targets).
    let results = tmp.path().join("results");
    let out = gpodo_on("run", &file, &results, &[]);
    common::assert_succeeded(&out, "");
    let predictions = tmp.path().join("predictions.csv");
    let out = Command::new(GPODO)
        .args(["--quiet", "predict", "--model"])
        .arg(&model)
        .arg("--input")
        .arg(results.join("residuals_test.csv"))
        .arg("--out")
        .arg(&predictions)
        .output()
        .unwrap();
    common::assert_succeeded(&out, "");
    let (header, values) = read_rows(&predictions).unwrap();
    assert_eq!(
        header,
        [
            "mean_res_vx",
            "mean_res_vy",
            "mean_res_vz",
            "var_res_vx",
            "var_res_vy",
            "var_res_vz"
        ]
    );
    let config = ExperimentConfig::from_path(&file).unwrap();
    let fitted = fit_model(&config, "exact GP: rbf [hyperopt.max_iters=30]").unwrap();
    assert_eq!(values.nrows(), fitted.test_predictions.mean.nrows());
    for i in 0..values.nrows() {
        for j in 0..3 {
            assert!(close(
                values.get(i, j),
                fitted.test_predictions.mean.get(i, j)
            ));
            assert!(close(
                values.get(i, 3 + j),
                fitted.test_predictions.variance.get(i, j)
            ));
        }
    }
}

#[test]
fn a_model_file_says_how_its_rows_were_made() {
    let tmp = tempfile::tempdir().unwrap();
    let file = write_config(tmp.path());
    let config = ExperimentConfig::from_path(&file).unwrap();
    let fitted = fit_model(&config, "ILGR").unwrap();
    let recipe = fitted.file.rows.clone().unwrap();
    // ExoTeR's simulated sensors run at 12.5 Hz; rows average 1 s; the
    // default weighted-Jacobian model, read back as the experiment's block.
    assert!((recipe.rate_hz.unwrap() - 12.5).abs() < 1e-9, "{recipe:?}");
    assert_eq!(recipe.window_secs, Some(1.0));
    assert!(!recipe.absolute_targets);
    let model: gpodo_kinematics::spec::MotionModelSpec =
        serde_json::from_value(recipe.motion_model.clone()).unwrap();
    assert_eq!(model, config.motion_model);
    let path = tmp.path().join("m.gpodo");
    fitted.file.save(&path).unwrap();
    assert_eq!(ModelFile::load(&path).unwrap().rows, Some(recipe));

    // A version-2 file (no recipe) reads as the current version without
    // one.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut v2: serde_json::Value = serde_json::from_str(&text).unwrap();
    v2["version"] = 2.into();
    v2.as_object_mut().unwrap().remove("rows");
    let old = tmp.path().join("v2.gpodo");
    std::fs::write(&old, v2.to_string()).unwrap();
    let loaded = ModelFile::load(&old).unwrap();
    assert_eq!(loaded.version, gpodo_regressors::model_file::MODEL_VERSION);
    assert_eq!(loaded.rows, None);
    assert_eq!(loaded.state, ModelFile::load(&path).unwrap().state);
}

#[test]
fn bad_model_files_and_rows_are_refused_with_their_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let file = write_config(tmp.path());
    let config = ExperimentConfig::from_path(&file).unwrap();
    let fitted = fit_model(&config, "ILGR").unwrap();
    let path = tmp.path().join("m.gpodo");
    fitted.file.save(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();

    let truncated = tmp.path().join("truncated.gpodo");
    std::fs::write(&truncated, &text[..text.len() / 2]).unwrap();
    let e = ModelFile::load(&truncated).unwrap_err().to_string();
    assert!(
        e.contains("truncated.gpodo") && e.contains("truncated"),
        "{e}"
    );

    let other_version = tmp.path().join("v99.gpodo");
    std::fs::write(
        &other_version,
        text.replacen("\"version\":3", "\"version\":99", 1),
    )
    .unwrap();
    let e = ModelFile::load(&other_version).unwrap_err().to_string();
    assert!(
        e.contains("model file version 99") && e.contains("reads versions 1 to 3"),
        "{e}"
    );

    let not_a_model = tmp.path().join("x.gpodo");
    std::fs::write(&not_a_model, "{\"name\": \"tiny\"}").unwrap();
    let e = ModelFile::load(&not_a_model).unwrap_err().to_string();
    assert!(e.contains("not a gpodo model file"), "{e}");

    // Rows without one of the model's columns.
    let loaded = ModelFile::load(&path).unwrap();
    let (names, rows) = &fitted.test_inputs;
    let mut renamed = names.clone();
    renamed[1] = "something_else".into();
    let e = loaded
        .predictor()
        .unwrap()
        .predict(&renamed, rows)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains(&format!("no column `{}`", names[1])), "{e}");

    // Kinds without a saved state, and unknown labels.
    let e = fit_model(&config, "k-NN (k=10)").unwrap_err().to_string();
    assert!(e.contains("cannot be saved"), "{e}");
    let e = fit_model(&config, "exact GP").unwrap_err().to_string();
    assert!(
        e.contains("no regressor labelled `exact GP`") && e.contains("ILGR"),
        "{e}"
    );
}
