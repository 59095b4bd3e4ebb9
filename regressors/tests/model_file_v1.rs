//! A model saved in version 1 of the `.gpodo` format (an exact GP with an
//! `rbf + linear` kernel, `tests/fixtures/model_v1/`, written by `gpodo
//! fit`) keeps loading and predicting what it predicted when it was saved
//! (`predictions.csv`, written by `gpodo predict` from `inputs.csv`): the
//! kernel's and the settings' saved shapes may not change under it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_regressors::model_file::{MODEL_VERSION, ModelFile};
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
    assert_eq!(file.version, 1);
    assert_eq!(MODEL_VERSION, 1, "a new version must still load this file");
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
