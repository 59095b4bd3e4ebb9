//! `kernel: auto` fits rbf, matern52 and each plus a linear kernel, and
//! keeps the highest log marginal likelihood. On a simulated rover whose
//! motion model has a wheel radius 4.5 % too large (a residual linear in
//! the wheel speeds), it keeps a kernel with a linear part that predicts
//! better than the RBF default; the linear part gains more likelihood
//! there than with the right radius (the control).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

mod common;

/// Runs RBF and `auto` on the simulated testbed with the motion model's
/// wheel radius `radius_m` (ExoTeR's is 0.07 m); returns the metrics.
fn run(dir: &Path, radius_m: f64) -> serde_json::Value {
    let exoter = Path::new(env!("CARGO_MANIFEST_DIR")).join("../kinematics/rovers/exoter.yaml");
    let text = std::fs::read_to_string(exoter).unwrap();
    assert!(text.contains("wheel_radius_m: 0.07\n"));
    let rover = dir.join(format!("rover-{radius_m}.yaml"));
    std::fs::write(
        &rover,
        text.replace(
            "wheel_radius_m: 0.07\n",
            &format!("wheel_radius_m: {radius_m}\n"),
        ),
    )
    .unwrap();
    let yaml = format!(
        "name: auto\ndataset: {{kind: simulated, preset: exoter-prl, seed: 3, training_runs: 2, training_run_secs: 120, test_max_secs: 300}}\nmotion_model: {{kind: weighted_jacobian, rover: {}}}\nregressors:\n  - kind: exact_gp\n    kernel: rbf\n  - kind: exact_gp\n    kernel: auto\n",
        rover.display()
    );
    let file = dir.join(format!("auto-{radius_m}.yaml"));
    std::fs::write(&file, yaml).unwrap();
    let out_dir = dir.join(format!("out-{radius_m}"));
    let out = common::gpodo_on("run", &file, &out_dir, &[]);
    common::assert_succeeded(&out, "");
    let text = std::fs::read_to_string(out_dir.join("metrics.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Every candidate of the `auto` fit with its log marginal likelihood.
fn candidates(metrics: &serde_json::Value) -> Vec<(String, f64)> {
    metrics["regressors"][1]["fit"]["kernel_candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c[0].as_str().unwrap().to_string(), c[1].as_f64().unwrap()))
        .collect()
}

/// How much more likelihood the best kernel with a linear part has than
/// the best without one.
fn linear_gain(tried: &[(String, f64)]) -> f64 {
    let best = |linear: bool| {
        tried
            .iter()
            .filter(|(k, _)| k.contains("linear") == linear)
            .map(|c| c.1)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    best(true) - best(false)
}

#[test]
fn auto_keeps_a_linear_part_for_a_wrong_wheel_radius_and_predicts_better_than_rbf() {
    let tmp = tempfile::tempdir().unwrap();
    let wrong = run(tmp.path(), 0.07 * 1.045);
    let tried = candidates(&wrong);
    let names: Vec<&str> = tried.iter().map(|c| c.0.as_str()).collect();
    assert_eq!(
        names,
        ["rbf", "matern52", "rbf + linear", "matern52 + linear"]
    );
    let (kept, lml) = tried
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .clone();
    assert!(kept.contains("+ linear"), "{tried:?}");
    // The fit kept is the winner: its LML is the one reported.
    let fit_lml = wrong["regressors"][1]["fit"]["objective"].as_f64().unwrap();
    assert_eq!(fit_lml, lml);
    let rmse = |m: &serde_json::Value, i: usize| {
        m["regressors"][i]["evaluation"]["pooled"]["rmse"]
            .as_f64()
            .unwrap()
    };
    assert!(
        rmse(&wrong, 1) < rmse(&wrong, 0),
        "auto {} against rbf {}",
        rmse(&wrong, 1),
        rmse(&wrong, 0)
    );
    // The linear part is worth more with the wrong radius than with the
    // right one.
    let right = run(tmp.path(), 0.07);
    let (gain_wrong, gain_right) = (linear_gain(&tried), linear_gain(&candidates(&right)));
    assert!(
        gain_wrong > gain_right + 2.0,
        "LML gain of a linear part: {gain_wrong:.2} with the wrong radius, {gain_right:.2} with the right one"
    );
    // The report names the kernel kept and every candidate's LML.
    let report =
        std::fs::read_to_string(tmp.path().join(format!("out-{}/report.md", 0.07 * 1.045)))
            .unwrap();
    assert!(
        report.contains(&format!("| exact GP: auto → {kept} |"))
            && report.contains(&format!(
                "`exact GP: auto` kept {kept}, the highest log marginal likelihood of rbf "
            )),
        "{report}"
    );
}
