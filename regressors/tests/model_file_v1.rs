//! A model saved in version 1 of the `.gpodo` format (an exact GP with an
//! `rbf + linear` kernel, `tests/fixtures/model_v1/`, written by `gpodo
//! fit`) keeps loading and predicting what it predicted when it was saved
//! (`predictions.csv`, written by `gpodo predict` from `inputs.csv`): the
//! kernel's and the settings' saved shapes may change only with a
//! conversion of version 1 on load.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_regressors::model_file::{MODEL_VERSION, ModelFile, SavedState};
use gpodo_traits::SampleMatrix;

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn a_version_1_model_file_loads_and_predicts_as_saved() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/model_v1");
    let file = ModelFile::load(&dir.join("exact_gp_rbf_linear.gpodo")).unwrap();
    // Read as the current version: the settings that version 1 kept at
    // the GP's top level are under `hyperopt` now.
    assert_eq!(file.version, MODEL_VERSION);
    let text = std::fs::read_to_string(dir.join("exact_gp_rbf_linear.gpodo")).unwrap();
    let v1: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v1["version"], 1);
    let SavedState::ExactGp(state) = &file.state else {
        panic!("not an exact GP: {:?}", file.state);
    };
    let flat = &v1["state"]["params"];
    assert_eq!(flat["max_iters"], state.params.hyperopt.max_iters);
    assert_eq!(flat["lbfgs_memory"], state.params.hyperopt.lbfgs_memory);
    assert_eq!(
        flat["bounds"]["lengthscale"][1],
        state.params.hyperopt.bounds.lengthscale[1]
    );
    let (columns, rows) = read_csv(&dir.join("inputs.csv"));
    let (_, expected) = read_csv(&dir.join("predictions.csv"));
    let inputs = SampleMatrix::from_rows(columns.len(), &rows).unwrap();
    let predicted = file
        .predictor()
        .unwrap()
        .predict(&columns, &inputs)
        .unwrap();
    let outputs = predicted.mean.ncols();
    for (i, want) in expected.iter().enumerate() {
        for c in 0..outputs {
            let (mean, var) = (predicted.mean.get(i, c), predicted.variance.get(i, c));
            assert!(
                (mean - want[c]).abs() <= 1e-12 * want[c].abs().max(1e-6),
                "mean {i},{c}: {mean} vs {}",
                want[c]
            );
            let v = want[outputs + c];
            assert!(
                (var - v).abs() <= 1e-12 * v.abs(),
                "variance {i},{c}: {var} vs {v}"
            );
        }
    }
}
