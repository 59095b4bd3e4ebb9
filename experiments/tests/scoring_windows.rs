//! `residuals.score_window_secs`: a model trained on one row per step is
//! scored on the test runs' windows, its per-step predictions averaged
//! with each window's weights. The parametric-only row predicts zero at
//! every step, so it must score exactly as on a dataset made of the same
//! windows.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

mod common;

fn run(dir: &Path, name: &str, residuals: &str) -> serde_json::Value {
    let yaml = format!(
        "name: {name}\ndataset: {{kind: simulated, preset: exoter-prl, seed: 5, training_runs: 1, training_run_secs: 60, test_max_secs: 120}}\nresiduals: {residuals}\nregressors:\n  - kind: zero\n  - kind: knn\n"
    );
    let file = dir.join(format!("{name}.yaml"));
    std::fs::write(&file, yaml).unwrap();
    let out_dir = dir.join(name);
    let out = common::gpodo_on("run", &file, &out_dir, &[]);
    common::assert_succeeded(&out, name);
    let text = std::fs::read_to_string(out_dir.join("metrics.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn pooled(m: &serde_json::Value, regressor: usize, score: &str) -> f64 {
    m["regressors"][regressor]["evaluation"]["pooled"][score]
        .as_f64()
        .unwrap()
}

#[test]
fn per_step_models_are_scored_on_the_same_windows_as_window_models() {
    let dir = tempfile::tempdir().unwrap();
    let steps = run(
        dir.path(),
        "steps",
        "{window_secs: null, score_window_secs: 1.0}",
    );
    let windows = run(dir.path(), "windows", "{window_secs: 1.0}");
    let n_samples = |m: &serde_json::Value, r: usize| {
        m["regressors"][r]["evaluation"]["n_samples"]
            .as_u64()
            .unwrap()
    };
    let n_windows = windows["dataset"]["n_test"].as_u64().unwrap();
    let n_steps = steps["dataset"]["n_test"].as_u64().unwrap();
    assert!(
        n_steps > 10 * n_windows,
        "{n_steps} steps, {n_windows} windows"
    );
    for r in 0..2 {
        assert_eq!(n_samples(&steps, r), n_windows);
        assert_eq!(n_samples(&windows, r), n_windows);
    }
    for score in ["rmse", "mae"] {
        let (a, b) = (pooled(&steps, 0, score), pooled(&windows, 0, score));
        assert!(
            (a - b).abs() <= 1e-15 * b.abs(),
            "parametric only {score}: {a} on averaged steps, {b} on windows"
        );
    }
    // The per-step nearest neighbours, averaged, are a real prediction.
    let knn = pooled(&steps, 1, "rmse");
    assert!(knn.is_finite() && knn > 0.0);
    let report = std::fs::read_to_string(dir.path().join("steps/report.md")).unwrap();
    assert!(
        report.contains("scored on the test runs' 1-s means"),
        "the report says how the rows were scored"
    );
}
